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

/// A relations file: about 100 bytes a relation.
pub const RELATIONS_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "relations file",
    limit_name: "slam_eval::RELATIONS_INPUT",
    max_bytes: 64 << 20,
};

/// Faster than any robot the relations were measured on drives (the benchmark's reach
/// 1.6 m/s), metres per second of the stamps' span.
pub const MAX_RELATION_SPEED_M_S: f64 = 10.0;
/// What a relation may move besides that speed: the benchmark's stamps are off by up to a
/// scan's time (Intel moves 0.35 m over 5 ms).
pub const RELATION_SLACK_M: f64 = 1.0;
/// No angle of a relation is more than a turn.
const MAX_RELATION_ANGLE: f64 = std::f64::consts::TAU;

/// A relations file as read: its relations, each once, and what was noted on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct RelationsRead {
    pub relations: Vec<Relation>,
    /// `(line, first line)` of each line that repeats an earlier one (counted once).
    pub duplicates: Vec<(usize, usize)>,
    /// Relations whose `t2` is before their `t1`: a motion backwards in time, scored as such.
    pub backwards: usize,
}

impl RelationsRead {
    /// One line each for what the reading noted, for a console.
    pub fn notes(&self, path: &Path) -> Vec<String> {
        let mut notes = Vec::new();
        if self.backwards > 0 {
            notes.push(format!(
                "{}: {} relation(s) with t2 before t1, scored as motions backwards in time",
                path.display(),
                self.backwards
            ));
        }
        for (line, first) in &self.duplicates {
            notes.push(format!(
                "{}, line {line}: repeats line {first}; counted once",
                path.display()
            ));
        }
        notes
    }
}

/// Reads a relations file; blank lines and `#` comments are skipped, a repeated line is
/// counted once.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>, EvalError> {
    Ok(read_relations_noted(path)?.relations)
}

/// [`read_relations`] with what it noted: repeated lines, motions backwards in time. A
/// non-finite or absurd value (an angle beyond a turn, a motion faster than
/// [`MAX_RELATION_SPEED_M_S`] past [`RELATION_SLACK_M`]), or two lines with the same stamps
/// and different motions, is refused naming its line.
pub fn read_relations_noted(path: &Path) -> Result<RelationsRead, EvalError> {
    let mut read = RelationsRead {
        relations: Vec::new(),
        duplicates: Vec::new(),
        backwards: 0,
    };
    let mut seen = std::collections::HashMap::new();
    for (line, mut relation) in parse_lines(path, &RELATIONS_INPUT, parse_relation)? {
        relation.line = line;
        let malformed = |reason| EvalError::Malformed {
            path: path.to_path_buf(),
            line,
            reason,
        };
        match seen.entry((relation.t1_ns, relation.t2_ns)) {
            std::collections::hash_map::Entry::Occupied(first) => {
                let first: &Relation = &read.relations[*first.get()];
                if first.delta != relation.delta {
                    return Err(malformed(format!(
                        "the stamps of line {} with another motion",
                        first.line
                    )));
                }
                read.duplicates.push((line, first.line));
                continue;
            }
            std::collections::hash_map::Entry::Vacant(slot) => {
                slot.insert(read.relations.len());
            }
        }
        read.backwards += usize::from(relation.t2_ns < relation.t1_ns);
        read.relations.push(relation);
    }
    if read.relations.is_empty() {
        return Err(EvalError::Empty {
            path: path.to_path_buf(),
            what: "relations",
        });
    }
    Ok(read)
}

/// Refuses a motion no robot makes between the two stamps, or an angle beyond a turn.
fn check_plausible(t1_ns: u64, t2_ns: u64, values: &[f64; 6]) -> Result<(), String> {
    let [x, y, z, roll, pitch, yaw] = *values;
    for (angle, name) in [(roll, "roll"), (pitch, "pitch"), (yaw, "yaw")] {
        if angle.abs() > MAX_RELATION_ANGLE {
            return Err(format!("{name} {angle} rad is more than a turn"));
        }
    }
    let span_s = t2_ns.abs_diff(t1_ns) as f64 * 1e-9;
    let reach = RELATION_SLACK_M + MAX_RELATION_SPEED_M_S * span_s;
    let moved = x.hypot(y).hypot(z);
    if moved > reach {
        // Short either way: an absurd value has hundreds of digits.
        let moved = if moved < 1e6 {
            format!("{moved:.3}")
        } else {
            format!("{moved:.3e}")
        };
        return Err(format!(
            "a motion of {moved} m in {span_s:.3} s: more than {reach:.3} m \
             ({RELATION_SLACK_M} m and {MAX_RELATION_SPEED_M_S} m/s)"
        ));
    }
    Ok(())
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
    check_plausible(t1_ns, t2_ns, &values)?;
    let [x, y, z, roll, pitch, yaw] = values;
    Ok(Relation {
        line: 0,
        t1_ns,
        t2_ns,
        delta: from_xyz_rpy([x, y, z], roll, pitch, yaw),
    })
}
