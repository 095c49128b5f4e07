//! The system drawn from its state, recorded on `/scene` ([`Scene`]): each sample's
//! picture, for a viewer's 3D panel. The runtime does not know how a picture is encoded:
//! the application hands over a [`SceneMaker`] (`rig`'s draws a Foxglove `SceneUpdate`
//! with the `foxglove` crate, protobuf), so that the recorder needs no viewer's crates.

/// How a channel's messages are encoded: its schema (name, encoding, data) and the
/// messages' encoding, as MCAP and the Foxglove protocol declare them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Encoding {
    /// The schema's name (`foxglove.SceneUpdate`).
    pub schema_name: String,
    /// The schema's encoding (`protobuf`, `jsonschema`).
    pub schema_encoding: String,
    /// The schema (a serialised `FileDescriptorSet` for protobuf).
    pub schema: Vec<u8>,
    /// The messages' encoding (`protobuf`, `json`).
    pub message_encoding: String,
}

/// Draws pictures of one task's system.
pub trait Scene: Send {
    /// How the pictures are encoded.
    fn encoding(&self) -> Encoding;
    /// Writes the picture of state `x` at log time `t_ns` into `out` (emptied first). A
    /// component of `x` that is not finite is not drawn as a number: the picture shows
    /// it at rest or leaves it out.
    fn draw(&mut self, x: &[f64], t_ns: u64, out: &mut Vec<u8>);
}

/// Makes the [`Scene`] of a task's system.
pub type SceneMaker = fn(&plant::Task) -> Box<dyn Scene>;
