//! The JSON schema registered with each channel, derived from the struct that is encoded.

use schemars::JsonSchema;
use schemars::generate::SchemaSettings;

/// Schema encoding of every channel (MCAP's well-known `jsonschema`).
pub const SCHEMA_ENCODING: &str = "jsonschema";
/// Message encoding of every channel (MCAP's well-known `json`).
pub const MESSAGE_ENCODING: &str = "json";

/// The JSON schema of `T` titled `name`, every sub-schema inlined: viewers that read a
/// schema to list a message's fields (Foxglove's) need not resolve `$ref`s.
pub fn schema_of<T: JsonSchema>(name: &str) -> serde_json::Value {
    let generator = SchemaSettings::draft07()
        .with(|s| s.inline_subschemas = true)
        .into_generator();
    let mut schema = generator.into_root_schema_for::<T>();
    schema.insert("title".to_owned(), name.into());
    schema.to_value()
}

/// A channel of the recording: its topic, the name of its schema and the type encoded on it.
pub trait ChannelMessage: serde::Serialize + JsonSchema + Sized {
    /// MCAP topic.
    const TOPIC: &'static str;
    /// Schema name: `foxglove.*` where Foxglove's schema fits, `slam.*` for our own.
    const SCHEMA: &'static str;

    /// The schema text registered with the channel.
    fn schema() -> serde_json::Value {
        schema_of::<Self>(Self::SCHEMA)
    }
}
