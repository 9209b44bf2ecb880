//! Jointed rigid bodies: the shared [`model::Model`] and the joint-coordinate reference dynamics [`joint_space`].
pub mod joint_space;
pub mod model;
