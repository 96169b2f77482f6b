//! The progress line: map-sink reports `status key=value ...`, we show it.

use std::collections::BTreeMap;

/// The latest progress of a run, from map-sink's status lines.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Progress {
    fields: BTreeMap<String, String>,
}

impl Progress {
    /// Takes in a `key=value key=value` line; unknown keys are kept, malformed words ignored.
    pub fn update(&mut self, line: &str) {
        for word in line.split_whitespace() {
            if let Some((key, value)) = word.split_once('=') {
                self.fields.insert(key.to_owned(), value.to_owned());
            }
        }
    }

    /// Scans map-sink has seen a pose for.
    pub fn frames(&self) -> u64 {
        self.get("frames").and_then(|v| v.parse().ok()).unwrap_or(0)
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.fields.get(key).map(String::as_str)
    }

    /// One human line, e.g. `523/1200 scans | 40.1 scans/s | latency 1.2 ms | ...`.
    pub fn render(&self, total: Option<u64>) -> String {
        let frames = match total {
            Some(total) if total > 0 => format!("{}/{total} scans", self.frames()),
            _ => format!("{} scans", self.frames()),
        };
        let mut parts = vec![frames];
        if let Some(rate) = self.get("scans_per_s") {
            parts.push(format!("{rate} scans/s"));
        }
        if let Some(latency) = self.get("latency_ms") {
            parts.push(format!("latency {latency} ms"));
        }
        if let (Some(neff), Some(n)) = (self.get("neff"), self.get("particles")) {
            parts.push(format!("Neff {neff}/{n}"));
        }
        if let Some(map) = self.get("map") {
            parts.push(format!("map {map} corners"));
        }
        if let Some(state) = self.get("localization") {
            parts.push(format!("localization {state}"));
        }
        parts.join(" | ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_what_it_was_told() {
        let mut progress = Progress::default();
        progress.update(
            "frames=12 scans_per_s=39.8 latency_ms=1.25 neff=80.2 particles=100 map=7 junk",
        );
        assert_eq!(progress.frames(), 12);
        assert_eq!(
            progress.render(Some(1200)),
            "12/1200 scans | 39.8 scans/s | latency 1.25 ms | Neff 80.2/100 | map 7 corners"
        );
        progress.update("frames=13");
        assert_eq!(progress.frames(), 13);
        progress.update("localization=converged");
        assert!(
            progress
                .render(None)
                .ends_with("| map 7 corners | localization converged")
        );
    }
}
