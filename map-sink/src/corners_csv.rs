//! The map as a CSV table, one corner a row.

use std::fmt::Write;

use slam_geom::MapCorner;

/// The unique entries of the symmetric covariance over `(x, y, heading, angle)`, in the
/// order of the CSV columns, with their index in the row-major 4x4 matrix.
const COVARIANCE_COLUMNS: [(&str, usize); 10] = [
    ("cov_xx", 0),
    ("cov_xy", 1),
    ("cov_xh", 2),
    ("cov_xa", 3),
    ("cov_yy", 5),
    ("cov_yh", 6),
    ("cov_ya", 7),
    ("cov_hh", 10),
    ("cov_ha", 11),
    ("cov_aa", 15),
];

/// The header line, without the newline.
pub fn corners_csv_header() -> String {
    let mut header = String::from("x,y,heading,angle");
    for (name, _) in COVARIANCE_COLUMNS {
        header.push(',');
        header.push_str(name);
    }
    header.push_str(",observations");
    header
}

/// The whole CSV: header and one row per corner, numbers in shortest round-trip form.
pub fn corners_csv(corners: &[MapCorner]) -> String {
    let mut csv = corners_csv_header();
    csv.push('\n');
    for c in corners {
        // Writing to a String cannot fail.
        let _ = write!(csv, "{},{},{},{}", c.x, c.y, c.heading, c.angle);
        for (_, index) in COVARIANCE_COLUMNS {
            let _ = write!(csv, ",{}", c.covariance[(index / 4, index % 4)]);
        }
        let _ = writeln!(csv, ",{}", c.observations);
    }
    csv
}
