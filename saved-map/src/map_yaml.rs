//! `map.yaml`, the description of a map image as ROS map_server and nav2's map_io read it,
//! and the trinary pixel convention that goes with it.
//!
//! A reader turns a pixel `v` into an occupancy `occ = (255 - v) / 255` (`v / 255` with
//! `negate: 1`); `occ > occupied_thresh` is occupied, `occ < free_thresh` free, anything
//! else unknown. Trinary images hold three values only: 0 (occupied, occ 1.0), 254 (free,
//! occ 0.004) and 205 (unknown, occ 0.196). `free_thresh` is therefore written as 0.196, as
//! ROS 1's map_saver does and nav2's does since 2025 (navigation2 pull request 5278): with
//! the 0.25 older nav2 savers wrote, a reader takes every unknown pixel for free space.
//! The thresholds that decided which cell became which pixel are the grid's
//! ([`back_end::occupancy_grid::OCCUPIED_PROBABILITY`],
//! [`back_end::occupancy_grid::FREE_PROBABILITY`]).

pub use back_end::occupancy_grid::{
    CellState, FREE_PIXEL, OCCUPIED_PIXEL, UNKNOWN_PIXEL, trinary_pixel,
};
/// `occupied_thresh` as written.
pub const OCCUPIED_THRESH: f64 = 0.65;
/// `free_thresh` as written: just below the unknown pixel's occupancy, 50 / 255.
pub const FREE_THRESH: f64 = 0.196;

/// How a reader turns pixels into cells (map_server's `mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode {
    Trinary,
    Scale,
    Raw,
}

/// The fields of a map_server YAML.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// The image file, relative to the YAML's directory unless absolute.
    pub image: String,
    pub mode: MapMode,
    /// Metres per pixel.
    pub resolution: f64,
    /// The pose `[x, y, yaw]` of the lower-left corner of the lower-left pixel, metres and
    /// radians, in the map frame.
    pub origin: [f64; 3],
    pub negate: bool,
    pub occupied_thresh: f64,
    pub free_thresh: f64,
}

/// A line of a map YAML that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum YamlError {
    #[error("line {line}: {reason}")]
    Line { line: usize, reason: String },
    #[error("no `{0}` key: not a map_server map description")]
    MissingKey(&'static str),
}

impl MapYaml {
    /// The description of a trinary image of a grid at `resolution` whose lower-left cell
    /// corner is at `origin`.
    pub fn trinary(image: &str, resolution: f64, origin: [f64; 2]) -> Self {
        Self {
            image: image.to_owned(),
            mode: MapMode::Trinary,
            resolution,
            origin: [origin[0], origin[1], 0.0],
            negate: false,
            occupied_thresh: OCCUPIED_THRESH,
            free_thresh: FREE_THRESH,
        }
    }

    /// The YAML text, one key a line as map_saver writes it. Numbers are rounded to a
    /// nanometre so an origin of `-241 * 0.05` reads `-12.05`, not `-12.050000000000001`.
    pub fn to_text(&self) -> String {
        let mode = match self.mode {
            MapMode::Trinary => "trinary",
            MapMode::Scale => "scale",
            MapMode::Raw => "raw",
        };
        let n = |v: f64| {
            let r = (v * 1e9).round() / 1e9;
            // `-0` would be a valid but odd-looking number.
            if r == 0.0 { 0.0 } else { r }
        };
        format!(
            "image: {}\nmode: {mode}\nresolution: {}\norigin: [{}, {}, {}]\nnegate: {}\noccupied_thresh: {}\nfree_thresh: {}\n",
            self.image,
            n(self.resolution),
            n(self.origin[0]),
            n(self.origin[1]),
            n(self.origin[2]),
            u8::from(self.negate),
            self.occupied_thresh,
            self.free_thresh,
        )
    }

    /// Reads the flat `key: value` YAML map_server reads: `#` comments, scalars plain or
    /// quoted, `origin` as a flow sequence. `image`, `resolution` and `origin` must be
    /// there; `mode` defaults to trinary, `negate` to 0 and the thresholds to the ones
    /// written here. Unknown keys are ignored, as map_server ignores them.
    pub fn parse(text: &str) -> Result<Self, YamlError> {
        let mut image = None;
        let mut mode = MapMode::Trinary;
        let mut resolution = None;
        let mut origin = None;
        let mut negate = false;
        let mut occupied_thresh = OCCUPIED_THRESH;
        let mut free_thresh = FREE_THRESH;
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let fail = |reason: String| YamlError::Line { line, reason };
            let content = strip_comment(raw).trim_end();
            if content.trim().is_empty() || content.trim() == "---" {
                continue;
            }
            if content.starts_with(char::is_whitespace) {
                return Err(fail(
                    "indented: a map description is one flat mapping".into(),
                ));
            }
            let Some((key, value)) = content.split_once(':') else {
                return Err(fail(format!("`{}` is not `key: value`", content.trim())));
            };
            let value = unquote(value.trim());
            let number = |what: &str| {
                value
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| fail(format!("{what} `{value}` is not a number")))
            };
            match key.trim() {
                "image" => {
                    if value.is_empty() {
                        return Err(fail("`image` is empty".into()));
                    }
                    image = Some(value.to_owned());
                }
                "mode" => {
                    mode = match value {
                        "trinary" => MapMode::Trinary,
                        "scale" => MapMode::Scale,
                        "raw" => MapMode::Raw,
                        other => return Err(fail(format!("unknown mode `{other}`"))),
                    }
                }
                "resolution" => {
                    let r = number("resolution")?;
                    if r <= 0.0 {
                        return Err(fail(format!("resolution {r} is not positive")));
                    }
                    resolution = Some(r);
                }
                "origin" => origin = Some(parse_origin(value).map_err(fail)?),
                "negate" => {
                    negate = match value {
                        "0" | "false" => false,
                        "1" | "true" => true,
                        other => return Err(fail(format!("negate `{other}` is not 0 or 1"))),
                    }
                }
                "occupied_thresh" => occupied_thresh = number("occupied_thresh")?,
                "free_thresh" => free_thresh = number("free_thresh")?,
                _ => {}
            }
        }
        Ok(Self {
            image: image.ok_or(YamlError::MissingKey("image"))?,
            mode,
            resolution: resolution.ok_or(YamlError::MissingKey("resolution"))?,
            origin: origin.ok_or(YamlError::MissingKey("origin"))?,
            negate,
            occupied_thresh,
            free_thresh,
        })
    }

    /// A pixel read by the map_server rules (trinary and scale alike; scale's in-between
    /// shades, which carry a probability, count as unknown here).
    pub fn cell_state(&self, pixel: u8) -> CellState {
        let shade = f64::from(pixel) / 255.0;
        let occ = if self.negate { shade } else { 1.0 - shade };
        if occ > self.occupied_thresh {
            CellState::Occupied
        } else if occ < self.free_thresh {
            CellState::Free
        } else {
            CellState::Unknown
        }
    }
}

/// The line without a `#` comment (a `#` that starts the line or follows whitespace, as in
/// YAML), ignoring quotes: no map_server key holds a `#`.
fn strip_comment(line: &str) -> &str {
    let bytes = line.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'#' && (i == 0 || bytes[i - 1].is_ascii_whitespace()) {
            return &line[..i];
        }
    }
    line
}

fn unquote(value: &str) -> &str {
    for q in ['"', '\''] {
        if let Some(inner) = value.strip_prefix(q).and_then(|v| v.strip_suffix(q)) {
            return inner;
        }
    }
    value
}

fn parse_origin(value: &str) -> Result<[f64; 3], String> {
    let inner = value
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| format!("origin `{value}` is not `[x, y, yaw]`"))?;
    let numbers: Vec<f64> = inner
        .split(',')
        .map(|p| p.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("origin `{value}` holds something other than numbers"))?;
    <[f64; 3]>::try_from(numbers)
        .map_err(|n| format!("origin has {} numbers, expected 3 (x, y, yaw)", n.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_written_text_reads_back_and_keeps_map_saver_layout() {
        let yaml = MapYaml::trinary("map.pgm", 0.05, [-241.0 * 0.05, 3.0 * 0.05]);
        let text = yaml.to_text();
        assert_eq!(
            text,
            "image: map.pgm\nmode: trinary\nresolution: 0.05\norigin: [-12.05, 0.15, 0]\n\
             negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
        );
        let back = MapYaml::parse(&text).unwrap();
        assert_eq!(back.image, "map.pgm");
        assert_eq!(back.origin, [-12.05, 0.15, 0.0]);
        assert_eq!(back.resolution, 0.05);
    }

    #[test]
    fn the_three_pixels_read_as_the_three_states() {
        let yaml = MapYaml::trinary("map.pgm", 0.05, [0.0, 0.0]);
        assert_eq!(yaml.cell_state(OCCUPIED_PIXEL), CellState::Occupied);
        assert_eq!(yaml.cell_state(FREE_PIXEL), CellState::Free);
        assert_eq!(yaml.cell_state(UNKNOWN_PIXEL), CellState::Unknown);
        // With the 0.25 of older nav2 savers, unknown would read as free.
        let old = MapYaml {
            free_thresh: 0.25,
            ..yaml
        };
        assert_eq!(old.cell_state(UNKNOWN_PIXEL), CellState::Free);
    }

    #[test]
    fn other_peoples_files_parse_and_broken_ones_name_the_line() {
        let text = "# saved by hand\nimage: \"office map.pgm\"   # quoted\nresolution: 0.1\n\
                    origin: [ 1.5 , -2, 0.3 ]\nnegate: 1\noccupied_thresh: 0.7\nfree_thresh: 0.2\nextra: ok\n";
        let yaml = MapYaml::parse(text).unwrap();
        assert_eq!(yaml.image, "office map.pgm");
        assert_eq!(yaml.origin, [1.5, -2.0, 0.3]);
        assert!(yaml.negate);
        assert_eq!(yaml.mode, MapMode::Trinary);
        assert_eq!(
            MapYaml::parse("image: a.pgm\nresolution: fine\n"),
            Err(YamlError::Line {
                line: 2,
                reason: "resolution `fine` is not a number".into()
            })
        );
        assert_eq!(
            MapYaml::parse("image: a.pgm\norigin: [0, 0]\nresolution: 1\n"),
            Err(YamlError::Line {
                line: 2,
                reason: "origin has 2 numbers, expected 3 (x, y, yaw)".into()
            })
        );
        // A foreign file (here JSON) lacks the keys.
        assert_eq!(
            MapYaml::parse("{\"format\": \"something else\"}"),
            Err(YamlError::MissingKey("image"))
        );
        assert_eq!(
            MapYaml::parse("image: a.pgm\nresolution: 0.05\n"),
            Err(YamlError::MissingKey("origin"))
        );
    }
}
