//! Contact with Coulomb friction in the multibody step: hard, as impulses, in both kicks.
//!
//! A contact `k` between bodies `a` and `b` (either may be the world) has a gap `φ_k(q)`
//! along its normal `n_k` (from `b` to `a`) and two tangents. Its force acts in both
//! half-kicks of the RATTLE step (docs/theory/multibody.md §6):
//!
//! ```text
//! λ-kick / drift:  φ_k(q⁺) ≥ 0,  σ_n,k ≥ 0,  φ_k(q⁺) σ_n,k = 0        (no penetration at the end)
//!                  stick: the contact's material points do not slide over the step,
//!                         |σ_t,k| ≤ µ_k σ_n,k;   slip: σ_t,k = −µ_k σ_n,k s_k (s_k the slip's direction)
//! μ-kick:          v_n,k⁺ ≥ 0,  σ_n,k ≥ 0 with complementarity (plastic), and stick
//!                  (v_t,k⁺ = 0) or slip (σ_t,k on the cone's edge against v_t,k⁺)
//! ```
//!
//! with `σ` the contact force over the half-kick (impulse `(h/2) σ`). Both problems have the
//! form `r = r₀ + W σ` with `W = (h/2) D P M⁻¹ Dᵀ` (`D` the contact rows, `P` the projection
//! on the joints' constraints): the velocity one is linear, the position one is solved by an
//! outer iteration that re-runs the drift (with its joint solve) at each new `σ`, `r` being
//! the gap and the slide over the step divided by `h`. Each linear problem is solved by
//! projected Gauss–Seidel over the contacts (`cone.rs`; each contact's own 3x3 problem in
//! `block.rs`: its normal force, then its friction force as the exact minimiser over
//! Coulomb's disc `|σ_t| ≤ µ σ_n`, the elliptic cone), to a stated tolerance; a step whose
//! solve does not converge is an error.
//! No velocity bias, no Baumgarte term, no softness: a body at rest stays at rest to the
//! solver's tolerance, and a body on a slope below its friction angle does not creep.
//!
//! Collision detection (`detect.rs`) uses `parry3d` (contact manifolds for spheres, capsules,
//! boxes, cylinders and half-spaces; two boxes face on face are clipped in `boxes.rs`), a
//! uniform grid as the broad phase, and MuJoCo's filters:
//! `contype`/`conaffinity`, `<contact><exclude>`, no contact between geoms of one body or
//! between a body and its parent (unless the parent is the world). The contacts of a step
//! are found at its start, with a margin of the distance the bodies can close over the step.
//!
//! Contacts are plastic unless the model gives Newton's restitution (global). When the
//! Gauss–Seidel sweeps stall, `polish.rs` and `newton.rs` finish the solve on a dense `W`.
//!
//! What is not simulated: per-geom restitution, torsional and rolling
//! friction, ellipsoid geoms and mesh geoms without their file (noted by the loader; a mesh
//! with its file touches as its convex hull), contacts in compositions and
//! the joint-space methods (noted: they run without contacts).
//!
//! Reference: docs/theory/multibody.md §6; J. J. Moreau, "Unilateral contact and dry
//! friction in finite freedom dynamics", 1988; D. Stewart, J. Trinkle, IJNME 39 (1996);
//! M. Anitescu, F. Potra, Nonlinear Dynamics 14 (1997).

mod block;
mod boxes;
mod cone;
mod detect;
mod islands;
mod newton;
mod polish;
mod response;
mod scratch;
mod step;
mod warm;

pub(super) use detect::ContactGeometry;
pub(super) use scratch::ContactScratch;

use super::shapes::Shape;

/// The shapes that touch and the contact options of a model.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Collision {
    /// The shapes that touch (each with [`Shape::collision`] set), posed in their bodies'
    /// frames (from the frame origin) or in the world.
    pub shapes: Vec<Shape>,
    /// Body pairs that never touch (MJCF `<contact><exclude>`), the world as `None`.
    pub exclude: Vec<(Option<usize>, Option<usize>)>,
    /// Contacts switched off (MJCF `<option><flag contact="disable"/>`).
    pub disabled: bool,
    /// Newton's coefficient of restitution `e` of every contact (0: plastic, the default;
    /// MJCF `<custom><numeric name="restitution" data="e"/>`): an impact separates at `e`
    /// times its approach speed.
    pub restitution: f64,
    /// Contacts between a body and its parent body kept (MJCF `<flag filterparent=
    /// "disable"/>`); by default a body never touches its parent unless that is the world.
    pub parent_contacts: bool,
}

impl Collision {
    /// Whether the model can have contacts at all: enabled, and two shapes on different
    /// bodies whose masks match.
    #[must_use]
    pub fn any(&self) -> bool {
        if self.disabled {
            return false;
        }
        let s = &self.shapes;
        (0..s.len()).any(|i| {
            (i + 1..s.len()).any(|j| {
                s[i].body != s[j].body
                    && match (&s[i].collision, &s[j].collision) {
                        (Some(a), Some(b)) => a.pairs_with(b),
                        _ => false,
                    }
            })
        })
    }
}
