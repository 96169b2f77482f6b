//! A map directory's grid read by the ROS map_server rules (ROS 1 image_loader, nav2
//! map_io), with a parser of the tests' own, not with the saved-map crate's code (with which
//! map-sink writes it and slam-proc reads it).

use std::collections::HashMap;

/// The keys map_server reads from a map YAML.
pub struct MapDescription {
    pub image: String,
    pub mode: String,
    pub resolution: f64,
    pub origin: [f64; 3],
    pub negate: bool,
    pub occupied_thresh: f64,
    pub free_thresh: f64,
}

/// A flat `key: value` YAML as map_server writes and reads it.
pub fn parse_yaml(text: &str) -> MapDescription {
    let mut keys = HashMap::new();
    for line in text.lines() {
        let line = line.split(" #").next().unwrap_or("").trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (key, value) = line.split_once(':').expect("key: value");
        keys.insert(key.trim().to_owned(), value.trim().to_owned());
    }
    let get = |key: &str| {
        keys.get(key)
            .unwrap_or_else(|| panic!("map.yaml has no {key}"))
            .clone()
    };
    let number = |key: &str| -> f64 {
        get(key)
            .parse()
            .unwrap_or_else(|_| panic!("{key} is not a number"))
    };
    let origin: Vec<f64> = get("origin")
        .trim_start_matches('[')
        .trim_end_matches(']')
        .split(',')
        .map(|v| v.trim().parse().expect("origin number"))
        .collect();
    MapDescription {
        image: get("image"),
        mode: keys
            .get("mode")
            .cloned()
            .unwrap_or_else(|| "trinary".into()),
        resolution: number("resolution"),
        origin: [origin[0], origin[1], origin[2]],
        negate: get("negate") == "1",
        occupied_thresh: number("occupied_thresh"),
        free_thresh: number("free_thresh"),
    }
}

/// A binary PGM: width, height and the pixels, rows from the top.
pub fn parse_pgm(bytes: &[u8]) -> (usize, usize, Vec<u8>) {
    assert_eq!(&bytes[..2], b"P5", "not a binary PGM");
    let mut at = 2;
    let mut fields = Vec::new();
    while fields.len() < 3 {
        while bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        if bytes[at] == b'#' {
            while bytes[at] != b'\n' {
                at += 1;
            }
            continue;
        }
        let start = at;
        while bytes[at].is_ascii_digit() {
            at += 1;
        }
        let field: usize = std::str::from_utf8(&bytes[start..at])
            .expect("ASCII")
            .parse()
            .expect("a number");
        fields.push(field);
    }
    at += 1; // the single whitespace after the maximum value
    let (width, height, maxval) = (fields[0], fields[1], fields[2]);
    assert_eq!(maxval, 255);
    let pixels = bytes[at..].to_vec();
    assert_eq!(pixels.len(), width * height, "pixel count");
    (width, height, pixels)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cell {
    Occupied,
    Free,
    Unknown,
}

/// map_server's reading of one pixel (ROS 1 image_loader, nav2 map_io): occupancy from the
/// shade, then the thresholds.
pub fn read_pixel(map: &MapDescription, pixel: u8) -> Cell {
    let shade = f64::from(pixel) / 255.0;
    let occ = if map.negate { shade } else { 1.0 - shade };
    if occ > map.occupied_thresh {
        Cell::Occupied
    } else if occ < map.free_thresh {
        Cell::Free
    } else {
        Cell::Unknown
    }
}
