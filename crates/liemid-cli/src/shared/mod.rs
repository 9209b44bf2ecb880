//! Machinery every domain's command uses: how a command fails and reports a study
//! (`command`), plots drawn with plotters (`plot`), interrupts and the progress bar
//! (`interrupt`). Output paths and trajectory files (`output`), checkpoints, `.npy`, extended
//! XYZ, scenario tables, the 3-D page (`view`), CPU time and the DOP853 settings are the
//! application crate's, named here as the commands use them.

pub mod command;
pub mod interrupt;
pub mod plot;

pub use liemid_app::shared::{checkpoint, cpu_time, dop853, npy, output, toml_table, view, xyz};
