//! Machinery every domain uses: how an input file is read (`input`), the step bound of every
//! run (`bounds`) and whether its storage fits (`memory`), output paths and trajectory files (`output`), checkpoints,
//! `.npy` and extended XYZ files, the TOML tables of scenario files (`toml_table`), what a
//! plot shows (`figure`), a study's progress (`progress`), the 3-D page of a run (`view`),
//! CPU time for studies (`cpu_time`) and the DOP853 baseline's settings (`dop853`).

pub mod bounds;
pub mod checkpoint;
pub mod cpu_time;
pub mod dop853;
pub mod figure;
pub mod input;
pub mod memory;
pub mod npy;
pub mod output;
pub mod progress;
pub mod toml_table;
pub mod view;
pub mod xyz;
