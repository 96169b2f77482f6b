//! Why a world was refused; each variant names the problem and where it is.

/// A world that cannot be simulated. `path` fields are JSON paths such as `walls[2][5]`.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("unknown world {name:?} (built in: hall, office, corridor)")]
    UnknownBuiltin { name: String },
    /// Not a built-in world, and not a world file that can be read.
    #[error("not a built-in world (hall, office, corridor), nor a world file")]
    Read(#[from] stage_kit::InputError),
    #[error("world JSON does not parse at line {line}, column {column}: {message}")]
    Json {
        line: usize,
        column: usize,
        message: String,
    },
    #[error("world file lacks the key {key:?}")]
    MissingKey { key: &'static str },
    #[error("world file has an unknown key {key:?} (known: walls, waypoints, speed)")]
    UnknownKey { key: String },
    #[error("{path}: expected {expected}")]
    WrongType {
        path: String,
        expected: &'static str,
    },
    #[error("{path}: {value} is not a finite number")]
    NonFinite { path: String, value: f64 },
    #[error("waypoints: {count} given, at least 2 are needed")]
    TooFewWaypoints { count: usize },
    #[error("walls: the world has no walls")]
    NoWalls,
    #[error("walls[{index}]: a wall needs at least 2 points, it has {points}")]
    ShortWall { index: usize, points: usize },
    #[error("{path}: repeats the point before it (a segment of zero length)")]
    ZeroLengthSegment { path: String },
    #[error("speed: {speed} m/s is not positive")]
    NonPositiveSpeed { speed: f64 },
}
