//! Flexible beams: `liemid beam` and `liemid beam work-precision` (`command`). The
//! structure file (`scenario`) and the sampled runs and study against Newmark (`study`)
//! are the application crate's, named here as the command uses them.

pub mod command;

pub use liemid_app::beam::{scenario, study};
