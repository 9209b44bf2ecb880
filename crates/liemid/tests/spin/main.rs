//! The spin domain (one test binary): lattices, exact solutions, orders and threads (`lattice`),
//! the Dzyaloshinskii-Moriya interaction (`dmi`), and the symplecticity of every method
//! (`poisson`).

mod dmi;
mod lattice;
mod poisson;
