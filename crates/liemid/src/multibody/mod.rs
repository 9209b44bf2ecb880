//! Multibody systems: rigid bodies connected by joints, in maximal coordinates.
//!
//! - [`model`]: the plain-data model (bodies, joints, gravity, starting coordinates).
//! - [`mjcf`]: load a MuJoCo MJCF file into a [`model::Model`].
//! - [`urdf`]: load a ROS URDF file into a [`model::Model`].

pub mod mjcf;
pub mod model;
pub mod urdf;
mod xml;

pub use xml::Loaded;
