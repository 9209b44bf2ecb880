//! Machinery every domain's command uses: how a command fails and reports a study
//! (`command`), output paths and trajectory files (`output`), checkpoints, `.npy` and
//! extended XYZ files, plots, interrupts with the progress bar, the 3-D page of a run
//! (`view`), the thread's CPU time for studies (`cpu_time`) and the DOP853 baseline's
//! settings (`dop853`).

pub mod checkpoint;
pub mod command;
pub mod cpu_time;
pub mod dop853;
pub mod interrupt;
pub mod npy;
pub mod output;
pub mod plot;
pub mod toml_table;
pub mod view;
pub mod xyz;
