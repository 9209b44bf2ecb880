//! Jointed rigid bodies: the model files, scenario files and built-in problems
//! (`scenario`) and the 3-D page of a run (`view`).

pub mod scenario;
pub mod view;
