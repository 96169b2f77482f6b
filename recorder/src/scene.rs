//! Foxglove's `foxglove.SceneUpdate`: entities of spheres and lines that the 3D panel draws
//! as they are, without a panel of ours. Only the primitives the recorder draws have a type
//! here; the other kinds Foxglove's schema requires are always empty ([`OtherPrimitives`]).
//!
//! A scene is display data derived from messages recorded whole on their own channels, so
//! its numbers are rounded ([`mm`], [`Quaternion`] to four digits): they print short and
//! compress well, and nothing is read back from them.

use std::borrow::Cow;
use std::marker::PhantomData;

use schemars::{JsonSchema, Schema, SchemaGenerator, json_schema};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use crate::geometry::{Pose, Quaternion, Vector3};
use crate::schema::ChannelMessage;
use crate::stamp::Time;

/// The topic a scene is recorded on.
pub trait SceneTopic {
    const TOPIC: &'static str;
}

/// A [`SceneUpdate`] on the topic `T` names.
#[derive(Debug)]
pub struct Scene<T> {
    pub update: SceneUpdate,
    topic: PhantomData<T>,
}

impl<T> Scene<T> {
    pub fn new(update: SceneUpdate) -> Self {
        Self {
            update,
            topic: PhantomData,
        }
    }
}

/// Exactly the update.
impl<T> Serialize for Scene<T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.update.serialize(serializer)
    }
}

impl<T> JsonSchema for Scene<T> {
    fn schema_name() -> Cow<'static, str> {
        SceneUpdate::schema_name()
    }

    fn json_schema(generator: &mut SchemaGenerator) -> Schema {
        SceneUpdate::json_schema(generator)
    }
}

impl<T: SceneTopic> ChannelMessage for Scene<T> {
    const TOPIC: &'static str = T::TOPIC;
    const SCHEMA: &'static str = "foxglove.SceneUpdate";
}

/// An update of the scene a topic holds: entities to delete, then entities to add or
/// replace (by `id`, per topic).
#[derive(Debug, Serialize, JsonSchema)]
pub struct SceneUpdate {
    pub deletions: Vec<SceneEntityDeletion>,
    pub entities: Vec<SceneEntity>,
}

/// Removes entities published before `timestamp`: the one with `id` (`kind` 0,
/// `MATCHING_ID`) or all of the topic's (`kind` 1, `ALL`).
#[derive(Debug, Serialize, JsonSchema)]
pub struct SceneEntityDeletion {
    pub timestamp: Time,
    #[serde(rename = "type")]
    #[schemars(range(max = 1))]
    pub kind: u8,
    pub id: String,
}

/// Deletion of the entity with the given id.
pub const DELETE_MATCHING_ID: u8 = 0;

/// A thing in the scene, in `frame_id`, shown until replaced, deleted or its `lifetime` has
/// passed (a zero lifetime: forever).
#[derive(Debug, Serialize, JsonSchema)]
pub struct SceneEntity {
    #[serde(flatten)]
    pub placement: Placement,
    pub metadata: Vec<KeyValue>,
    /// The ellipses.
    pub spheres: Vec<SpherePrimitive>,
    /// Segments and arms.
    pub lines: Vec<LinePrimitive>,
    #[serde(flatten)]
    pub others: OtherPrimitives,
}

/// Where and how long an entity is shown, and the id that a later entity replaces it by.
#[derive(Debug, Serialize, JsonSchema)]
pub struct Placement {
    pub timestamp: Time,
    pub frame_id: String,
    /// Unique among the entities of the topic.
    pub id: String,
    pub lifetime: Duration,
    /// false: the entity stays where its frame was at `timestamp`.
    pub frame_locked: bool,
}

/// The primitive kinds the recorder does not draw: Foxglove's schema requires them, always
/// empty here.
#[derive(Debug, Default)]
pub struct OtherPrimitives;

/// Their fields in a `SceneEntity`.
pub const OTHER_PRIMITIVES: [&str; 6] = [
    "arrows",
    "cubes",
    "cylinders",
    "triangles",
    "texts",
    "models",
];

impl Serialize for OtherPrimitives {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(OTHER_PRIMITIVES.len()))?;
        for kind in OTHER_PRIMITIVES {
            map.serialize_entry(kind, &[(); 0])?;
        }
        map.end()
    }
}

impl JsonSchema for OtherPrimitives {
    fn schema_name() -> Cow<'static, str> {
        "OtherPrimitives".into()
    }

    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        let empty = serde_json::json!({ "type": "array", "maxItems": 0 });
        let properties: serde_json::Map<String, serde_json::Value> = OTHER_PRIMITIVES
            .iter()
            .map(|kind| ((*kind).to_owned(), empty.clone()))
            .collect();
        json_schema!({
            "type": "object",
            "properties": properties,
            "required": OTHER_PRIMITIVES,
        })
    }
}

impl SceneEntity {
    /// An entity of `spheres` and `lines` at `stamp_ns` in `frame_id`, shown until it is
    /// replaced or deleted, fixed where its frame was then.
    pub fn new(
        stamp_ns: u64,
        frame_id: &str,
        id: String,
        spheres: Vec<SpherePrimitive>,
        lines: Vec<LinePrimitive>,
    ) -> Self {
        Self {
            placement: Placement {
                timestamp: Time::from_ns(stamp_ns),
                frame_id: frame_id.to_owned(),
                id,
                lifetime: Duration::FOREVER,
                frame_locked: false,
            },
            metadata: Vec::new(),
            spheres,
            lines,
            others: OtherPrimitives,
        }
    }
}

#[derive(Debug, Serialize, JsonSchema)]
pub struct KeyValue {
    pub key: String,
    pub value: String,
}

/// Foxglove's `duration`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
pub struct Duration {
    pub sec: i32,
    #[schemars(range(max = 999_999_999))]
    pub nsec: u32,
}

impl Duration {
    /// A zero lifetime: the entity stays until it is replaced or deleted.
    pub const FOREVER: Self = Self { sec: 0, nsec: 0 };
}

/// An ellipsoid: `size` is its extent along the axes of `pose`.
#[derive(Debug, Serialize, JsonSchema)]
pub struct SpherePrimitive {
    pub pose: Pose,
    pub size: Vector3,
    pub color: Color,
}

/// Lines through `points` in the frame of `pose`: a strip (`kind` 0), a loop (1) or
/// separate segments (2, a list).
#[derive(Debug, Serialize, JsonSchema)]
pub struct LinePrimitive {
    #[serde(rename = "type")]
    #[schemars(range(max = 2))]
    pub kind: u8,
    pub pose: Pose,
    /// Metres, or pixels when `scale_invariant`.
    pub thickness: f64,
    pub scale_invariant: bool,
    pub points: Vec<Vector3>,
    pub color: Color,
    /// Per point; empty: every point in `color`.
    pub colors: Vec<Color>,
    /// Indices into `points`; empty: every point in order.
    pub indices: Vec<u32>,
}

/// Connected segments through the points in order.
pub const LINE_STRIP: u8 = 0;
/// Separate segments, one per pair of points.
pub const LINE_LIST: u8 = 2;

impl LinePrimitive {
    /// Lines of `kind` through `points`, `thickness` pixels wide at any zoom.
    pub fn new(kind: u8, points: Vec<Vector3>, thickness: f64, color: Color) -> Self {
        Self {
            kind,
            pose: Pose::IDENTITY,
            thickness,
            scale_invariant: true,
            points,
            color,
            colors: Vec::new(),
            indices: Vec::new(),
        }
    }
}

/// RGBA, each in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Color {
    pub r: f64,
    pub g: f64,
    pub b: f64,
    pub a: f64,
}

impl Color {
    /// Opaque.
    pub const fn rgb(r: f64, g: f64, b: f64) -> Self {
        Self { r, g, b, a: 1.0 }
    }

    /// The same colour, `a` opaque (0: invisible).
    pub const fn with_alpha(self, a: f64) -> Self {
        Self { a, ..self }
    }
}

/// `x` rounded to the millimetre (or to 1e-3 of whatever unit it is in).
pub fn mm(x: f64) -> f64 {
    (x * 1e3).round() / 1e3
}

/// A point of the plane, in millimetres, on the z = 0 plane.
pub fn point(x: f64, y: f64) -> Vector3 {
    Vector3 {
        x: mm(x),
        y: mm(y),
        z: 0.0,
    }
}

/// A planar position and heading rounded for display: the position to the millimetre, the
/// quaternion to four digits.
pub fn planar_pose(x: f64, y: f64, yaw: f64) -> Pose {
    let q = Quaternion::from_yaw(yaw);
    let four = |v: f64| (v * 1e4).round() / 1e4;
    Pose {
        position: point(x, y),
        orientation: Quaternion {
            z: four(q.z),
            w: four(q.w),
            ..q
        },
    }
}
