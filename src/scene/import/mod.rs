//! Scene import: drawings made in other programs turned into an `ashlar.scene/1` [`SceneSpec`],
//! which then goes through `scene::validate` exactly like a user's JSON file. Sits before
//! validation in the flow (drawing → spec → scene); the CLI (`ashlar scene import`) and the
//! service (`POST /v1/scenes/import`) only call [`dxf::import`].
//!
//! [`SceneSpec`]: super::SceneSpec
pub mod dxf;
