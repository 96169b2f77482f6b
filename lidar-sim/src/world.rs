//! The simulated world: wall polylines, the path the vehicle drives and its speed, read from
//! a built-in layout or a JSON file and checked before anything uses it.

use std::path::Path;

use serde::Serialize;
use serde_json::Value;

use crate::WorldError;
use crate::builtin;

/// Names accepted by [`World::builtin`].
pub const BUILTIN_WORLDS: [&str; 3] = ["hall", "office", "corridor"];

/// A world file: a few bytes per wall, so this holds hundreds of thousands of walls.
pub const WORLD_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "world file",
    limit_name: "lidar_sim::WORLD_INPUT",
    max_bytes: 16 << 20,
};

/// Walls and the waypoint path, metres in the world frame.
///
/// JSON form: `{"walls": [[[x, y], ...], ...], "waypoints": [[x, y], ...], "speed": 1.0}`.
/// A wall is a polyline; a closed polygon repeats its first point. `speed` (m/s) is
/// optional and defaults to 1. Waypoints that end on the first make a loop, which several
/// [`crate::Laps`] drive round and round; any other route they drive back and forth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct World {
    pub walls: Vec<Vec<[f64; 2]>>,
    pub waypoints: Vec<[f64; 2]>,
    pub speed: f64,
}

impl World {
    /// One of [`BUILTIN_WORLDS`].
    pub fn builtin(name: &str) -> Result<World, WorldError> {
        match name {
            "hall" => Ok(builtin::hall()),
            "office" => Ok(builtin::office()),
            "corridor" => Ok(builtin::corridor()),
            _ => Err(WorldError::UnknownBuiltin { name: name.into() }),
        }
    }

    /// A built-in world by name, or else the world file at `arg`.
    pub fn resolve(arg: &str) -> Result<World, WorldError> {
        if BUILTIN_WORLDS.contains(&arg) {
            World::builtin(arg)
        } else {
            World::load(arg)
        }
    }

    /// Reads and checks a JSON world file.
    pub fn load(path: impl AsRef<Path>) -> Result<World, WorldError> {
        let path = path.as_ref();
        let text = WORLD_INPUT.read_to_string(path)?;
        World::from_json_str(&text)
    }

    /// Parses and checks a JSON world. Parsed by hand from a `Value` so that every refusal
    /// can name the JSON path of the offending item.
    pub fn from_json_str(text: &str) -> Result<World, WorldError> {
        let value: Value = serde_json::from_str(text).map_err(|e| {
            let full = e.to_string();
            let suffix = format!(" at line {} column {}", e.line(), e.column());
            WorldError::Json {
                line: e.line(),
                column: e.column(),
                message: full.strip_suffix(&suffix).unwrap_or(&full).to_string(),
            }
        })?;
        let Value::Object(map) = value else {
            return Err(WorldError::WrongType {
                path: "(top level)".into(),
                expected: "an object with walls, waypoints and speed",
            });
        };
        if let Some(key) = map
            .keys()
            .find(|k| !matches!(k.as_str(), "walls" | "waypoints" | "speed"))
        {
            return Err(WorldError::UnknownKey { key: key.clone() });
        }
        let walls_value = map
            .get("walls")
            .ok_or(WorldError::MissingKey { key: "walls" })?;
        let walls = array(walls_value, "walls", "an array of walls")?
            .iter()
            .enumerate()
            .map(|(i, w)| points(w, &format!("walls[{i}]")))
            .collect::<Result<Vec<_>, _>>()?;
        let waypoints = points(
            map.get("waypoints")
                .ok_or(WorldError::MissingKey { key: "waypoints" })?,
            "waypoints",
        )?;
        let speed = match map.get("speed") {
            Some(v) => number(v, "speed")?,
            None => 1.0,
        };
        let world = World {
            walls,
            waypoints,
            speed,
        };
        world.validate()?;
        Ok(world)
    }

    /// Checks what the ray caster, the corner finder and the vehicle rely on. Worlds built
    /// in code should pass through here too.
    pub fn validate(&self) -> Result<(), WorldError> {
        if self.walls.is_empty() {
            return Err(WorldError::NoWalls);
        }
        for (i, wall) in self.walls.iter().enumerate() {
            if wall.len() < 2 {
                return Err(WorldError::ShortWall {
                    index: i,
                    points: wall.len(),
                });
            }
            check_polyline(wall, &format!("walls[{i}]"))?;
        }
        check_polyline(&self.waypoints, "waypoints")?;
        if self.waypoints.len() < 2 {
            return Err(WorldError::TooFewWaypoints {
                count: self.waypoints.len(),
            });
        }
        if !self.speed.is_finite() {
            return Err(WorldError::NonFinite {
                path: "speed".into(),
                value: self.speed,
            });
        }
        if self.speed <= 0.0 {
            return Err(WorldError::NonPositiveSpeed { speed: self.speed });
        }
        Ok(())
    }

    /// Every wall segment as `[start, end]`.
    pub fn segments(&self) -> impl Iterator<Item = [[f64; 2]; 2]> + '_ {
        self.walls
            .iter()
            .flat_map(|w| w.windows(2).map(|p| [p[0], p[1]]))
    }

    /// Length of the waypoint polyline, metres.
    pub fn path_length(&self) -> f64 {
        self.waypoints
            .windows(2)
            .map(|p| (p[1][0] - p[0][0]).hypot(p[1][1] - p[0][1]))
            .sum()
    }
}

fn check_polyline(points: &[[f64; 2]], path: &str) -> Result<(), WorldError> {
    for (j, p) in points.iter().enumerate() {
        for (k, &v) in p.iter().enumerate() {
            if !v.is_finite() {
                return Err(WorldError::NonFinite {
                    path: format!("{path}[{j}][{k}]"),
                    value: v,
                });
            }
        }
        if j > 0 && points[j - 1] == *p {
            return Err(WorldError::ZeroLengthSegment {
                path: format!("{path}[{j}]"),
            });
        }
    }
    Ok(())
}

fn array<'a>(v: &'a Value, path: &str, expected: &'static str) -> Result<&'a [Value], WorldError> {
    v.as_array()
        .map(Vec::as_slice)
        .ok_or_else(|| WorldError::WrongType {
            path: path.into(),
            expected,
        })
}

fn points(v: &Value, path: &str) -> Result<Vec<[f64; 2]>, WorldError> {
    array(v, path, "an array of [x, y] points")?
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let path = format!("{path}[{j}]");
            match array(p, &path, "a point [x, y]")? {
                [x, y] => Ok([
                    number(x, &format!("{path}[0]"))?,
                    number(y, &format!("{path}[1]"))?,
                ]),
                _ => Err(WorldError::WrongType {
                    path,
                    expected: "a point [x, y]",
                }),
            }
        })
        .collect()
}

fn number(v: &Value, path: &str) -> Result<f64, WorldError> {
    v.as_f64().ok_or_else(|| WorldError::WrongType {
        path: path.into(),
        expected: "a number",
    })
}
