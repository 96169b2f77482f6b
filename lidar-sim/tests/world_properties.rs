//! Property tests of the world file decoder (`World::from_json_str`, what `--world FILE`
//! reads): whatever the bytes, it does not panic, keeps no more than the text holds, and
//! refuses a bad world with a typed error that names the JSON path at fault (or the line and
//! column of a syntax error); a valid world decodes to its values.

use lidar_sim::{World, WorldError};
use proptest::collection::vec;
use proptest::prelude::*;
use serde_json::{Value, json};

/// Decodes `text`; a world holds no more points than the text could write (`[0,0]` is five
/// bytes), and an error says something.
fn decode(text: &str) -> Result<Result<World, WorldError>, TestCaseError> {
    let result = World::from_json_str(text);
    match &result {
        Ok(world) => {
            let points: usize =
                world.walls.iter().map(Vec::len).sum::<usize>() + world.waypoints.len();
            prop_assert!(
                points * 5 <= text.len(),
                "{} points from {} bytes",
                points,
                text.len()
            );
        }
        Err(e) => prop_assert!(!e.to_string().is_empty()),
    }
    Ok(result)
}

/// A valid world: walls of distinct consecutive points, a path, a speed.
fn valid_world() -> impl Strategy<Value = Value> {
    let point = (-50i32..50, -50i32..50);
    let polyline = vec(point, 2..6).prop_map(|points| {
        // Consecutive points apart: each a unit step further along x from the one before.
        points
            .iter()
            .enumerate()
            .map(|(i, (x, y))| json!([f64::from(*x) + i as f64 * 100.0, f64::from(*y)]))
            .collect::<Vec<_>>()
    });
    (vec(polyline.clone(), 1..5), polyline, 0.1f64..5.0).prop_map(
        |(walls, waypoints, speed)| json!({"walls": walls, "waypoints": waypoints, "speed": speed}),
    )
}

/// How a valid world is spoiled, and what its error must name.
#[derive(Debug, Clone)]
enum Spoil {
    DropKey(&'static str),
    UnknownKey,
    /// A coordinate of wall `i` (modulo the walls) made a string, null or an object.
    BadCoordinate(usize, Value),
    /// Wall `i` cut to one point.
    ShortWall(usize),
    /// The first point of wall `i` written twice.
    RepeatedPoint(usize),
    /// A speed that is not positive.
    Speed(f64),
    /// The text cut after this fraction of its bytes.
    Truncate(f64),
}

fn spoil() -> impl Strategy<Value = Spoil> {
    prop_oneof![
        prop::sample::select(vec!["walls", "waypoints"]).prop_map(Spoil::DropKey),
        Just(Spoil::UnknownKey),
        (
            any::<usize>(),
            prop::sample::select(vec![json!("1"), Value::Null, json!({}), json!([1])])
        )
            .prop_map(|(i, v)| Spoil::BadCoordinate(i, v)),
        any::<usize>().prop_map(Spoil::ShortWall),
        any::<usize>().prop_map(Spoil::RepeatedPoint),
        prop::sample::select(vec![0.0, -1.0, -1e-9]).prop_map(Spoil::Speed),
        (0.0f64..0.99).prop_map(Spoil::Truncate),
    ]
}

/// Fragments world files are made of, so random texts reach past the JSON syntax.
const FRAGMENTS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "\"walls\"",
    "\"waypoints\"",
    "\"speed\"",
    "\"x\"",
    "0",
    "1",
    "-1",
    "1.5",
    "1e400",
    "-0",
    "null",
    "true",
    " ",
    "\n",
    "[0,0]",
    "[1,1]",
    "[[0,0],[1,0]]",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_bytes_are_a_world_or_an_error(bytes in vec(any::<u8>(), 0..3000)) {
        let _ = decode(&String::from_utf8_lossy(&bytes))?;
    }

    #[test]
    fn texts_of_world_fragments_are_a_world_or_an_error(
        parts in vec(prop::sample::select(FRAGMENTS), 0..200),
    ) {
        let _ = decode(&parts.concat())?;
    }

    #[test]
    fn deep_nesting_is_refused_without_exhausting_the_stack(depth in 1usize..100_000) {
        let text = format!("{{\"walls\": {}{}}}", "[".repeat(depth), "]".repeat(depth));
        prop_assert!(decode(&text)?.is_err());
    }

    #[test]
    fn a_valid_world_decodes_to_its_values(world in valid_world()) {
        let text = world.to_string();
        let decoded = decode(&text)?;
        let Ok(decoded) = decoded else {
            return Err(TestCaseError::fail(format!("{text}: {:?}", decoded)));
        };
        prop_assert_eq!(decoded.walls.len(), world["walls"].as_array().map_or(0, Vec::len));
        // Within an ulp: serde_json's default float parser is not exact (it has a
        // `float_roundtrip` feature for that), and metres need no more.
        let speed = world["speed"].as_f64().unwrap_or(f64::NAN);
        prop_assert!((decoded.speed - speed).abs() <= 2.0 * f64::EPSILON * speed, "{} {}", decoded.speed, speed);
        prop_assert_eq!(
            decoded.waypoints.len(),
            world["waypoints"].as_array().map_or(0, Vec::len)
        );
    }

    #[test]
    fn a_spoilt_world_is_refused_naming_what_is_wrong(world in valid_world(), spoil in spoil()) {
        let mut world = world;
        let walls = world["walls"].as_array().map_or(1, Vec::len);
        let (text, named) = match spoil.clone() {
            Spoil::DropKey(key) => {
                world.as_object_mut().map(|o| o.remove(key));
                (world.to_string(), format!("lacks the key \"{key}\""))
            }
            Spoil::UnknownKey => {
                world["walls_"] = json!(1);
                (world.to_string(), "unknown key \"walls_\"".to_owned())
            }
            Spoil::BadCoordinate(i, value) => {
                let i = i % walls;
                world["walls"][i][0][1] = value;
                (world.to_string(), format!("walls[{i}][0]"))
            }
            Spoil::ShortWall(i) => {
                let i = i % walls;
                let first = world["walls"][i][0].clone();
                world["walls"][i] = json!([first]);
                (world.to_string(), format!("walls[{i}]: a wall needs at least 2 points"))
            }
            Spoil::RepeatedPoint(i) => {
                let i = i % walls;
                let first = world["walls"][i][0].clone();
                if let Some(points) = world["walls"][i].as_array_mut() {
                    points.insert(0, first);
                }
                (world.to_string(), format!("walls[{i}][1]: repeats the point before it"))
            }
            Spoil::Speed(speed) => {
                world["speed"] = json!(speed);
                (world.to_string(), "speed: ".to_owned())
            }
            Spoil::Truncate(fraction) => {
                let text = world.to_string();
                let cut = (text.len() as f64 * fraction) as usize;
                (text[..cut].to_owned(), "world JSON does not parse at line 1, column".to_owned())
            }
        };
        let Err(error) = decode(&text)? else {
            return Err(TestCaseError::fail(format!("{spoil:?} accepted: {text}")));
        };
        let message = error.to_string();
        prop_assert!(message.contains(&named), "{:?}: {} (expected {})", spoil, message, named);
    }
}
