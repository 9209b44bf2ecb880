//! The spin domain (one test binary): lattices, exact solutions, orders and threads (`lattice`),
//! and the Dzyaloshinskii-Moriya interaction (`dmi`).

mod dmi;
mod lattice;
