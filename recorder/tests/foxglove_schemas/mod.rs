//! Foxglove's well-known schemas as JSON schemas, written from Foxglove's documented fields
//! (foxglove.LaserScan, foxglove.FrameTransform, foxglove.PoseInFrame,
//! foxglove.PosesInFrame, foxglove.Grid): required fields, their types and the bounds of
//! `time` (foxglove.Grid from foxglove/schemas' `schemas/jsonschema/Grid.json`: its bounds
//! and `NumericType`'s values too); and foxglove.SceneUpdate as Foxglove publishes it
//! (`SceneUpdate.json`, unchanged from github.com/foxglove/foxglove-sdk,
//! `schemas/jsonschema/SceneUpdate.json` at commit 9ed45b16aac79dcd9a541d45d5baf7a9c45e36d7),
//! too deep to write out by hand without mistakes. The recorder's messages must validate
//! against these, not only against the schemas the recorder derives from its own structs.

use serde_json::{Value, json};

fn time() -> Value {
    json!({
        "type": "object",
        "properties": {
            "sec": { "type": "integer", "minimum": 0 },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
        }
    })
}

fn vector3() -> Value {
    json!({
        "type": "object",
        "properties": {
            "x": { "type": "number" }, "y": { "type": "number" }, "z": { "type": "number" }
        },
        "required": ["x", "y", "z"]
    })
}

fn quaternion() -> Value {
    json!({
        "type": "object",
        "properties": {
            "x": { "type": "number" }, "y": { "type": "number" },
            "z": { "type": "number" }, "w": { "type": "number" }
        },
        "required": ["x", "y", "z", "w"]
    })
}

fn pose() -> Value {
    json!({
        "type": "object",
        "properties": { "position": vector3(), "orientation": quaternion() },
        "required": ["position", "orientation"]
    })
}

pub fn laser_scan() -> Value {
    json!({
        "title": "foxglove.LaserScan",
        "type": "object",
        "properties": {
            "timestamp": time(),
            "frame_id": { "type": "string" },
            "pose": pose(),
            "start_angle": { "type": "number" },
            "end_angle": { "type": "number" },
            "ranges": { "type": "array", "items": { "type": "number" } },
            "intensities": { "type": "array", "items": { "type": "number" } }
        },
        "required": ["timestamp", "frame_id", "pose", "start_angle", "end_angle", "ranges",
                     "intensities"]
    })
}

pub fn frame_transform() -> Value {
    json!({
        "title": "foxglove.FrameTransform",
        "type": "object",
        "properties": {
            "timestamp": time(),
            "parent_frame_id": { "type": "string" },
            "child_frame_id": { "type": "string" },
            "translation": vector3(),
            "rotation": quaternion()
        },
        "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"]
    })
}

pub fn pose_in_frame() -> Value {
    json!({
        "title": "foxglove.PoseInFrame",
        "type": "object",
        "properties": {
            "timestamp": time(),
            "frame_id": { "type": "string" },
            "pose": pose()
        },
        "required": ["timestamp", "frame_id", "pose"]
    })
}

pub fn poses_in_frame() -> Value {
    json!({
        "title": "foxglove.PosesInFrame",
        "type": "object",
        "properties": {
            "timestamp": time(),
            "frame_id": { "type": "string" },
            "poses": { "type": "array", "items": pose() }
        },
        "required": ["timestamp", "frame_id", "poses"]
    })
}

fn vector2() -> Value {
    json!({
        "type": "object",
        "properties": { "x": { "type": "number" }, "y": { "type": "number" } },
        "required": ["x", "y"]
    })
}

/// `foxglove.PackedElementField`, its `type` a `foxglove.NumericType` (UNKNOWN 0, UINT8 1,
/// INT8 2, UINT16 3, INT16 4, UINT32 5, INT32 6, FLOAT32 7, FLOAT64 8).
fn packed_element_field() -> Value {
    let numeric_types: Vec<Value> = (0..=8).map(|v| json!({ "const": v })).collect();
    json!({
        "type": "object",
        "properties": {
            "name": { "type": "string" },
            "offset": { "type": "integer", "minimum": 0 },
            "type": { "oneOf": numeric_types }
        },
        "required": ["name", "offset", "type"]
    })
}

pub fn grid() -> Value {
    json!({
        "title": "foxglove.Grid",
        "type": "object",
        "properties": {
            "timestamp": time(),
            "frame_id": { "type": "string" },
            "pose": pose(),
            "column_count": { "type": "integer", "minimum": 0 },
            "cell_size": vector2(),
            "row_stride": { "type": "integer", "minimum": 0 },
            "cell_stride": { "type": "integer", "minimum": 0 },
            "fields": { "type": "array", "items": packed_element_field() },
            "data": { "type": "string", "contentEncoding": "base64" }
        },
        "required": ["timestamp", "frame_id", "pose", "column_count", "cell_size", "row_stride",
                     "cell_stride", "fields", "data"]
    })
}

pub fn scene_update() -> Value {
    serde_json::from_str(include_str!("SceneUpdate.json")).expect("Foxglove's schema is JSON")
}

/// Foxglove's schema of that name, if it is one of the six.
pub fn by_name(name: &str) -> Option<Value> {
    match name {
        "foxglove.Grid" => Some(grid()),
        "foxglove.LaserScan" => Some(laser_scan()),
        "foxglove.FrameTransform" => Some(frame_transform()),
        "foxglove.PoseInFrame" => Some(pose_in_frame()),
        "foxglove.PosesInFrame" => Some(poses_in_frame()),
        "foxglove.SceneUpdate" => Some(scene_update()),
        _ => None,
    }
}
