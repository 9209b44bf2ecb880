//! The [`Dipoles`] forces of the bodies one spatial domain owns, from the bodies it holds
//! (its own and the ghosts within reach of it), summed in the order of the whole system's
//! full Verlet list, so that a decomposition gives the same bits as one process.
//!
//! Each owned body's list is built by [`Dipoles::for_listed`] over a cell list of the
//! domain's bodies on the whole periodic box's grid (the grid depends on the box and the
//! reach only), the bodies indexed in increasing order of their identities: a cell then
//! holds the same bodies in the same order as in the whole system, restricted to those the
//! domain holds, and every body within reach of an owned body is held (the ghosts), so the
//! list, the pair kernel and the four-lane sum are those of the whole system's full list
//! (`Dipoles::compute` above `half_list_max_bodies`). The list is kept while no body has
//! moved more than half the skin (the caller decides, for the whole system, as
//! `Dipoles::update_list` does). Newton's third law is not used across domains: each pair
//! with a body on each side is evaluated on both (LAMMPS's `newton off` for ghost pairs),
//! and no force is sent back.
//!
//! Reference: S. Plimpton, Fast parallel algorithms for short-range molecular dynamics,
//! J. Comput. Phys. 117 (1995) 1-19 (spatial decomposition with ghost atoms).

use super::team::force_and_torque;
use super::{Dipoles, Scratch};
use crate::linalg::{Mat3, Vec3};
use crate::many::Configuration;

/// The neighbour lists of a domain's owned bodies and their evaluation (see the module).
#[derive(Debug, Default)]
pub struct DomainForces {
    scratch: Scratch,
    /// The neighbours of owned body `q` are `list[start[q]..start[q + 1]]` (indices into
    /// the domain's bodies).
    start: Vec<usize>,
    list: Vec<u32>,
    builds: u64,
}

impl DomainForces {
    /// Empty lists.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Build the lists of the bodies `owned` (indices into `position`, any order) from
    /// `position`: every body the domain holds, indexed in increasing order of identity, at
    /// the list's reference positions. `false`, with the lists emptied, when `model` has no
    /// cutoff or no periodic box, or the box is too small for a cell list at the reach
    /// `r_c + skin` (fewer than 3 cells of that width a side).
    pub fn build(&mut self, model: &Dipoles, position: &[Vec3], owned: &[u32]) -> bool {
        self.start.clear();
        self.list.clear();
        let (Some(reach), Some(_)) = (model.reach(), model.box_length) else {
            return false;
        };
        let c = Configuration {
            t: 0.0,
            mass: &[],
            free: &[],
            position,
            rotation: &[],
        };
        let Some(cells) = model.build_cells_of(&c, &mut self.scratch, reach) else {
            return false;
        };
        self.start.push(0);
        for &i in owned {
            let list = &mut self.list;
            model.for_listed(i as usize, &c, &cells, reach, |j| list.push(j as u32));
            self.start.push(self.list.len());
        }
        self.builds += 1;
        true
    }

    /// List builds so far.
    #[must_use]
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// Entries of the lists (pairs as seen from the owned bodies).
    #[must_use]
    pub fn entries(&self) -> usize {
        self.list.len()
    }

    /// The force (spatial) and torque (body frame) of each owned body `owned[q]` into
    /// `force[q]`, `torque[q]`: `position` and `dipole` (`R m` as the owner computed it) of
    /// every body the domain holds, `rotation[q]` the owned body's attitude. The lists must
    /// be those of [`DomainForces::build`] with the same `owned`. In parallel over fixed
    /// chunks with the `parallel` feature (the same bits for any thread count).
    ///
    /// # Panics
    /// If the slices' lengths do not match the lists (a caller's error).
    #[allow(clippy::too_many_arguments)]
    pub fn forces(
        &self,
        model: &Dipoles,
        position: &[Vec3],
        dipole: &[Vec3],
        owned: &[u32],
        rotation: &[Mat3],
        force: &mut [Vec3],
        torque: &mut [Vec3],
    ) {
        assert!(
            self.start.len() == owned.len() + 1 && force.len() == owned.len() && torque.len() == owned.len(),
            "domain lists built for another set of owned bodies"
        );
        let constants = model.constants();
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        let (avx, lane_kernel) = (crate::many::lanes::use_avx(), model.lane_kernel(&constants));
        crate::many::interactions::for_chunks(force, torque, |q, f, t| {
            let i = owned[q] as usize;
            let (xi, mi) = (position[i], dipole[i]);
            let neighbours = &self.list[self.start[q]..self.start[q + 1]];
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            let sums = crate::many::lanes::gather_pairs_x4(avx, &lane_kernel, xi, mi, position, dipole, neighbours)
                .unwrap_or_else(|| model.gather_pairs(&constants, xi, mi, position, dipole, neighbours));
            #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
            let sums = model.gather_pairs(&constants, xi, mi, position, dipole, neighbours);
            (*f, *t) = force_and_torque([sums.0, sums.1], &rotation[q], mi);
        });
    }
}
