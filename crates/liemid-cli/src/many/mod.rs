//! Many interacting rigid bodies: `liemid many` (`command`); its scenario file
//! (`scenario`) is the application crate's.

pub mod command;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod state;

pub use liemid_app::many::scenario;

/// Run `liemid many`: split over the ranks under `mpirun` (`mpi` feature), else in one
/// process. The choice is made here so that `command` and `mpi` import in one direction
/// only (`mpi` uses the command's settings).
pub fn run(cli: &command::ManyArgs) -> crate::shared::command::CmdResult {
    #[cfg(feature = "mpi")]
    if mpi::launched() {
        return mpi::many(cli);
    }
    command::many(cli)
}
