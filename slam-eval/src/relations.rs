//! Ground-truth relations (Kuemmerle et al. 2009): `t1 t2 x y z roll pitch yaw`, the pose
//! at `t2` in the frame of the pose at `t1`.

use std::path::Path;

use crate::error::EvalError;
use crate::pose::{Pose, from_xyz_rpy};
use crate::text::{expect_fields, number, parse_lines, stamp};

/// One relation of a relations file.
#[derive(Debug, Clone, PartialEq)]
pub struct Relation {
    /// 1-based line of the file, for reports.
    pub line: usize,
    pub t1_ns: u64,
    pub t2_ns: u64,
    /// `first_from_second`: the true motion from `t1` to `t2`.
    pub delta: Pose,
}

/// Reads a relations file; blank lines and `#` comments are skipped.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>, EvalError> {
    let relations: Vec<Relation> = parse_lines(path, parse_relation)?
        .into_iter()
        .map(|(line, mut relation)| {
            relation.line = line;
            relation
        })
        .collect();
    if relations.is_empty() {
        return Err(EvalError::Empty {
            path: path.to_path_buf(),
            what: "relations",
        });
    }
    Ok(relations)
}

fn parse_relation(fields: &[&str]) -> Result<Relation, String> {
    expect_fields(fields, "t1 t2 x y z roll pitch yaw")?;
    let t1_ns = stamp(fields[0], "t1")?;
    let t2_ns = stamp(fields[1], "t2")?;
    let mut values = [0.0; 6];
    for (value, (field, name)) in values.iter_mut().zip(
        fields[2..]
            .iter()
            .zip(["x", "y", "z", "roll", "pitch", "yaw"]),
    ) {
        *value = number(field, name)?;
    }
    let [x, y, z, roll, pitch, yaw] = values;
    Ok(Relation {
        line: 0,
        t1_ns,
        t2_ns,
        delta: from_xyz_rpy([x, y, z], roll, pitch, yaw),
    })
}
