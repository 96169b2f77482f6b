//! The saved occupancy grid as `foxglove.Grid`, once all its pieces are in.

use schemars::JsonSchema;
use serde::Serialize;

use ipc_types::GridGeometry;

use crate::geometry::{Pose, Vector3};
use crate::pose::MAP_FRAME;
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// Foxglove's `foxglove.Vector2`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Vector2 {
    pub x: f64,
    pub y: f64,
}

/// Foxglove's `foxglove.PackedElementField`: a named value at `offset` in each cell.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct PackedElementField {
    pub name: &'static str,
    pub offset: u32,
    /// Foxglove's `NumericType`: 1 is `UINT8`.
    #[serde(rename = "type")]
    pub numeric_type: u8,
}

/// Foxglove's `NumericType.UINT8`.
const UINT8: u8 = 1;
/// Bytes of a cell: red, green, blue, alpha.
const CELL_BYTES: usize = 4;

/// The grid map-sink wrote (`map.pgm`), one message at the end. Each cell is four bytes,
/// `red`, `green`, `blue` and `alpha`, the four fields with which Foxglove's 3D panel
/// colours a grid itself: red, green and blue are the cell's trinary pixel of `map.pgm`
/// (0 occupied, 254 free, 205 unknown), so the map looks as `map.png` does, and an unknown
/// cell is transparent. Rows from the lowest y, as Foxglove's `data` is (row-major from the
/// grid's origin corner); `map.pgm`'s first row is the highest. Foxglove's fields, then the
/// grid's size and geometry as map.yaml gives them.
#[derive(Debug, Serialize, JsonSchema)]
pub struct GridMessage {
    pub timestamp: Time,
    pub frame_id: &'static str,
    /// The lower-left corner of cell (0, 0) in the map.
    pub pose: Pose,
    pub column_count: u32,
    pub cell_size: Vector2,
    pub row_stride: u32,
    pub cell_stride: u32,
    pub fields: Vec<PackedElementField>,
    /// The cells, base64.
    pub data: String,
    /// Rows (`column_count` is the width).
    pub row_count: u32,
    /// Edge of a cell, metres.
    pub resolution: f64,
    /// map.yaml's `origin` (x, y; its yaw is 0).
    pub origin: [f64; 2],
}

impl ChannelMessage for GridMessage {
    const TOPIC: &'static str = "/map/grid";
    const SCHEMA: &'static str = "foxglove.Grid";
}

/// The back end's grid (its submaps at their solved poses) as it stands every few seconds
/// and at the end, in the form of [`GridMessage`].
#[derive(Debug, Serialize, JsonSchema)]
#[serde(transparent)]
pub struct GraphGridMessage(pub GridMessage);

impl ChannelMessage for GraphGridMessage {
    const TOPIC: &'static str = "/graph/grid";
    const SCHEMA: &'static str = "foxglove.Grid";
}

/// The trinary pixel of an unknown cell (map.pgm's 205).
const UNKNOWN_PIXEL: u8 = 205;

impl GridMessage {
    /// The grid `geometry` of `cells` (row by row from the lowest y, each a trinary pixel),
    /// at `stamp_ns`.
    pub fn new(stamp_ns: u64, geometry: &GridGeometry, cells: &[u8]) -> Self {
        let mut bytes = Vec::with_capacity(cells.len() * CELL_BYTES);
        for &pixel in cells {
            let alpha = if pixel == UNKNOWN_PIXEL { 0 } else { 255 };
            bytes.extend_from_slice(&[pixel, pixel, pixel, alpha]);
        }
        let field = |name, offset| PackedElementField {
            name,
            offset,
            numeric_type: UINT8,
        };
        Self {
            timestamp: Time::from_ns(stamp_ns),
            frame_id: MAP_FRAME,
            pose: Pose {
                position: Vector3 {
                    x: geometry.origin[0],
                    y: geometry.origin[1],
                    z: 0.0,
                },
                ..Pose::IDENTITY
            },
            column_count: geometry.width,
            cell_size: Vector2 {
                x: geometry.resolution,
                y: geometry.resolution,
            },
            row_stride: geometry.width * CELL_BYTES as u32,
            cell_stride: CELL_BYTES as u32,
            fields: vec![
                field("red", 0),
                field("green", 1),
                field("blue", 2),
                field("alpha", 3),
            ],
            data: base64(&bytes),
            row_count: geometry.height,
            resolution: geometry.resolution,
            origin: geometry.origin,
        }
    }
}

/// `bytes` in standard base64 with padding (RFC 4648), as JSON carries Foxglove's `bytes`.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut text = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for group in bytes.chunks(3) {
        let b = [
            group[0],
            group.get(1).copied().unwrap_or(0),
            group.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= group.len() {
                text.push(char::from(ALPHABET[((n >> (18 - 6 * i)) & 63) as usize]));
            } else {
                text.push('=');
            }
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_follows_rfc_4648() {
        // RFC 4648's test vectors.
        for (plain, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), encoded, "{plain}");
        }
        assert_eq!(base64(&[0xff, 0xfe, 0x00]), "//4A");
    }
}
