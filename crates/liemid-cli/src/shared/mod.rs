//! Machinery every domain's command uses: how a command fails and reports a study
//! (`command`), output paths and trajectory files (`output`), checkpoints, `.npy` and
//! extended XYZ files, plots, and interrupts with the progress bar.

pub mod checkpoint;
pub mod command;
pub mod interrupt;
pub mod npy;
pub mod output;
pub mod plot;
pub mod toml_table;
pub mod xyz;
