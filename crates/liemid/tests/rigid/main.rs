//! The rigid body about a fixed point (one test binary): adaptive steps, convergence orders, the
//! exact method, the free flow, invariants and structural claims.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/cotangent.rs"]
mod cotangent;

mod adaptive;
mod convergence;
mod exact_method;
mod free_flow;
mod invariants;
mod lie_poisson;
mod structure;
mod symplectic;
