//! Built-in [`Interaction`]s for many-body systems: independent bodies in uniform gravity,
//! and point dipoles with short-range repulsion.

use std::sync::Mutex;

use crate::linalg::{Mat3, Vec3};
use crate::many::half_list::{self, HalfList};
use crate::many::{Configuration, Interaction, TeamForces};

/// Each body on its own: a free body feels `F = m g`; a rotor (fixed point) feels the
/// gravity torque about its pivot `T = X × (Rᵀ m g)`, with `X` the centre of mass in the
/// body frame. With `g = 0`, torque-free bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Independent {
    /// Gravity (spatial).
    pub gravity: Vec3,
    /// Centre of mass of the rotors in their body frame, from the pivot.
    pub center_of_mass: Vec3,
}

impl Independent {
    /// Torque-free bodies.
    #[must_use]
    pub fn torque_free() -> Self {
        Independent {
            gravity: Vec3::ZERO,
            center_of_mass: Vec3::ZERO,
        }
    }
}

fn for_chunks(force: &mut [Vec3], torque: &mut [Vec3], f: impl Fn(usize, &mut Vec3, &mut Vec3) + Sync + Send) {
    #[cfg(feature = "parallel")]
    {
        use crate::many::CHUNK;
        use rayon::prelude::*;
        force
            .par_chunks_mut(CHUNK)
            .zip(torque.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(k, (fs, ts))| {
                for (j, (fo, to)) in fs.iter_mut().zip(ts.iter_mut()).enumerate() {
                    f(k * CHUNK + j, fo, to);
                }
            });
    }
    #[cfg(not(feature = "parallel"))]
    for (i, (fo, to)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        f(i, fo, to);
    }
}

impl Independent {
    /// Force and torque on one body of mass `mass`.
    #[inline]
    fn on_body(&self, mass: f64, free: bool, rotation: &Mat3) -> (Vec3, Vec3) {
        let w = self.gravity * mass;
        if free {
            (w, Vec3::ZERO)
        } else {
            (Vec3::ZERO, self.center_of_mass.cross(rotation.tr_mul_vec(w)))
        }
    }
}

impl Interaction for Independent {
    fn compute(&self, c: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        for_chunks(force, torque, |i, f, t| {
            (*f, *t) = self.on_body(c.mass[i], c.free[i], &c.rotation[i]);
        });
    }
    fn is_local(&self) -> bool {
        true
    }
    fn compute_local(&self, c: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        for (i, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
            (*f, *t) = self.on_body(c.mass[i], c.free[i], &c.rotation[i]);
        }
    }
    fn potential_energy(&self, c: Configuration<'_>) -> f64 {
        (0..c.mass.len())
            .map(|i| {
                let w = self.gravity * c.mass[i];
                if c.free[i] {
                    -w.dot(c.position[i])
                } else {
                    -w.dot(c.rotation[i] * self.center_of_mass)
                }
            })
            .sum()
    }
}

/// Point dipoles fixed in the body frames, with the Weeks-Chandler-Andersen repulsion:
///
/// ```text
/// U_dd = (μᵢ·μⱼ)/r³ − 3 (μᵢ·r)(μⱼ·r)/r⁵,   μᵢ = Rᵢ m
/// U_wca = 4ε[(σ/r)¹² − (σ/r)⁶] + ε   for r < 2^{1/6} σ
/// ```
///
/// (Gaussian units). Forces are gathered per body from its neighbours within the cutoff
/// (all pairs without one), found with a cell list, optionally in a periodic cubic box
/// (minimum image). The pair force is written symmetrically, so `F_ji = −F_ij` bit for bit
/// and the total momentum is kept to round-off.
///
/// With a cutoff `r_c`, the dipole-dipole energy is switched off smoothly over
/// `[r_s, r_c]` (by default `r_s = 0.8 r_c`, see [`Dipoles::with_switch_start`]):
///
/// ```text
/// U = S(r) U_dd + U_wca,   S = 1 for r ≤ r_s,   S = 0 for r ≥ r_c,
/// S = (r_c² − r²)² (r_c² + 2r² − 3r_s²) / (r_c² − r_s²)³   in between,
/// ```
///
/// so that the energy and the forces are continuous in `r` (`S` and `dS/dr` are; the
/// force gains `−U_dd ∇S`, the torque is `S` times the unswitched one). A plain truncation
/// makes the energy jump each time a pair crosses `r_c`, an error that no step size
/// removes; with the switch, the energy error of the fluid is the integrator's, `O(h²)`.
#[derive(Debug)]
pub struct Dipoles {
    /// The dipole moment in the body frame.
    pub moment: Vec3,
    /// WCA diameter σ.
    pub sigma: f64,
    /// WCA energy ε.
    pub epsilon: f64,
    /// Interaction cutoff (none: all pairs).
    pub cutoff: Option<f64>,
    /// Side of the periodic box (none: open space).
    pub box_length: Option<f64>,
    /// Where the switch begins, `r_s ≤ r_c` (used only with a cutoff and
    /// [`CutoffForm::Switched`]; `r_s = r_c` is a plain truncation).
    pub switch_start: f64,
    /// How the dipole energy goes to zero at the cutoff.
    pub cutoff_form: CutoffForm,
    /// The Verlet list's skin: with a cutoff, each body keeps the neighbours within
    /// `r_c + skin`, rebuilt once some body has moved more than `skin/2` since the last build
    /// (checked every evaluation); 0 rebuilds at every evaluation.
    pub skin: f64,
    /// Bodies up to which the half list is used ([`HALF_LIST_MAX_BODIES`] by default).
    pub half_list_max_bodies: usize,
    /// With the full list: keep the bodies' positions and dipoles in cell order (re-sorted
    /// at each list build), so that a body's neighbours are near it in memory; the
    /// results are the same bits either way (default `true`).
    pub spatial_sort: bool,
    scratch: Mutex<Scratch>,
}

#[derive(Debug, Default)]
struct Scratch {
    dipoles: Vec<Vec3>,
    /// The positions wrapped into the box in cell order (`wrapped[k]` is body `sorted[k]`),
    /// at the last cell build.
    wrapped: Vec<Vec3>,
    /// Each body's index in cell order (`sorted[cell_rank[i]] == i`).
    cell_rank: Vec<u32>,
    cell_start: Vec<usize>,
    sorted: Vec<usize>,
    cell_of: Vec<usize>,
    fill: Vec<usize>,
    /// The full Verlet list (empty while the half list is used): the neighbours of `i`
    /// within `r_c + skin` at the last build are
    /// `list[list_start[i]..list_start[i + 1]]`, in the cell traversal's fixed order.
    list_start: Vec<usize>,
    list: Vec<u32>,
    /// The half list (each pair once) over places, used up to
    /// [`Dipoles::half_list_max_bodies`] bodies.
    half: HalfList,
    /// The half list's sums: per place, the force and field from the partners it owns; per
    /// partition, its window of the partners' shares and the shares of one owner.
    own: Vec<[Vec3; 2]>,
    windows: Vec<Vec<[Vec3; 2]>>,
    shares: Vec<Vec<[Vec3; 2]>>,
    /// Per chunk of bodies, while the list is built in parallel: the neighbours found and
    /// each body's count (kept to reuse their memory).
    chunk_lists: Vec<(Vec<u32>, Vec<u32>)>,
    /// Positions at the last build (empty: no list yet).
    reference: Vec<Vec3>,
    /// With [`Dipoles::spatial_sort`] and the full list: the bodies in cell order
    /// (`order[k]` is a body, `rank[i]` its place), the list in those places, and each
    /// step's positions and dipoles in that order.
    order: Vec<u32>,
    rank: Vec<u32>,
    /// Whether the last build was asked to sort (it cannot without a cell list).
    sort_requested: bool,
    sorted_position: Vec<Vec3>,
    sorted_dipole: Vec<Vec3>,
    /// The force and field of each place, in cell order.
    sorted_sums: Vec<[Vec3; 2]>,
    /// Builds of the list, for diagnostics.
    builds: u64,
}

/// The default Verlet skin, as LAMMPS's default for Lennard-Jones units.
pub const DEFAULT_SKIN: f64 = 0.3;

/// Bodies up to which the forces use the half list (each pair once, Newton's third law:
/// the partners' shares through per-partition windows, [`crate::many`]'s `half_list`);
/// above, each body gathers its full list (each pair twice, no windows). Both run four
/// pairs at a time in AVX lanes where the processor has AVX (the same bits as their scalar
/// sums). Measured on this 2-core machine (2026-12-02, whole runs, list builds included),
/// the half list with windows against the full list: 0.96x the time at 10⁵ bodies on one
/// thread, 0.84x on two, and 0.84x at 10⁶ on two (229 against 274 ms a step), so it is
/// used at every size by default; the full list stays for a limit set lower. (With one
/// slot per pair instead of windows the half list lost above about 3·10⁴ bodies.)
pub const HALF_LIST_MAX_BODIES: usize = usize::MAX;

/// How the dipole-dipole energy is brought to zero at the cutoff `r_c`: `U = S(r) U_dd`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CutoffForm {
    /// `S = 1` up to the switch start `r_s`, then the cubic in `r²` of [`Dipoles`] down to
    /// 0 at `r_c`: the plain dipole inside `r_s`.
    #[default]
    Switched,
    /// Allen and Germano's shifted force, as LAMMPS's `lj/sf/dipole/sf`:
    /// `S = 1 − 4 (r/r_c)³ + 3 (r/r_c)⁴` over the whole range (`S` and `dS/dr` vanish at
    /// `r_c`); the forces are `−∇(S U_dd)` (LAMMPS writes them as the `afac`, `bfac` terms,
    /// which are the same), the torques `S` times the plain ones.
    ///
    /// Reference: M. P. Allen, G. Germano, Mol. Phys. 104 (2006) 3225.
    ShiftedForce,
}

impl CutoffForm {
    /// The name on the command line and in files.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            CutoffForm::Switched => "switched",
            CutoffForm::ShiftedForce => "shifted-force",
        }
    }
}

/// What one evaluation of the [`Dipoles`] pair sum needs of the model: the switch in squared
/// radii (`S = 1` up to `s2`, `0` beyond `c2`, `inv_width = 1/(c2 − s2)`), or for the shifted
/// force `1/r_c` (`inv_rc > 0`), and the periodic box side with its inverse.
struct PairConstants {
    c2: f64,
    s2: f64,
    inv_width: f64,
    inv_rc: f64,
    periodic: Option<(f64, f64)>,
}

/// A cell list over the bodies' bounding box (or the periodic box).
struct Cells<'a> {
    n: [usize; 3],
    origin: Vec3,
    size: f64,
    /// Cells each way the neighbours can lie in (cells at least `cutoff / reach` wide).
    reach: isize,
    /// The periodic box as the cells see it (`n · size`), and the bodies' positions wrapped
    /// into it in cell order (`wrapped[k]` is body `sorted[k]`; the positions themselves
    /// without a box): a candidate in a stencil cell reached across the box lies at its
    /// wrapped position plus the run's offset (multiples of `span`).
    span: f64,
    wrapped: &'a [Vec3],
    /// Each body's index in cell order.
    cell_rank: &'a [u32],
    periodic: bool,
    start: &'a [usize],
    sorted: &'a [usize],
}

/// The default start of the switch, as a fraction of the cutoff.
pub const DEFAULT_SWITCH_FRACTION: f64 = 0.8;

impl Dipoles {
    /// Dipoles `moment` (body frame) with WCA `(σ, ε)`, an optional cutoff and periodic box;
    /// with a cutoff, the dipole energy is switched off over `[0.8 r_c, r_c]`.
    ///
    /// # Errors
    /// A negative or non-finite `σ` or `ε`, a non-positive cutoff, or a box shorter than
    /// twice the cutoff.
    pub fn new(
        moment: Vec3,
        sigma: f64,
        epsilon: f64,
        cutoff: Option<f64>,
        box_length: Option<f64>,
    ) -> crate::Result<Self> {
        for (name, v) in [("sigma", sigma), ("epsilon", epsilon)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(crate::Error::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite and non-negative",
                });
            }
        }
        if let Some(c) = cutoff {
            if !(c.is_finite() && c > 0.0) {
                return Err(crate::Error::InvalidParameter {
                    name: "cutoff",
                    value: c,
                    reason: "must be finite and positive",
                });
            }
        }
        if let Some(l) = box_length {
            let c = cutoff.unwrap_or(f64::INFINITY);
            if !(l.is_finite() && l > 0.0 && 2.0 * c <= l) {
                return Err(crate::Error::InvalidParameter {
                    name: "box_length",
                    value: l,
                    reason: "must be finite, positive and at least twice the cutoff (minimum image)",
                });
            }
        }
        Ok(Dipoles {
            moment,
            sigma,
            epsilon,
            cutoff,
            box_length,
            switch_start: cutoff.map_or(0.0, |c| DEFAULT_SWITCH_FRACTION * c),
            cutoff_form: CutoffForm::Switched,
            spatial_sort: true,
            skin: DEFAULT_SKIN,
            half_list_max_bodies: HALF_LIST_MAX_BODIES,
            scratch: Mutex::new(Scratch::default()),
        })
    }

    /// The same model with the switch starting at `r_s` (`0 < r_s ≤ r_c`; `r_s = r_c`
    /// truncates the dipole sum at the cutoff without switching).
    ///
    /// # Errors
    /// No cutoff, or `r_s` outside `(0, r_c]`.
    pub fn with_switch_start(mut self, r_s: f64) -> crate::Result<Self> {
        let c = self.cutoff.unwrap_or(f64::NAN);
        if !(r_s > 0.0 && r_s <= c) {
            return Err(crate::Error::InvalidParameter {
                name: "switch_start",
                value: r_s,
                reason: "needs a cutoff and must lie in (0, cutoff]",
            });
        }
        self.switch_start = r_s;
        Ok(self)
    }

    /// The minimum-image separation `a − b`. The nearest integer of `q = r/L` is taken as
    /// `(q + M) − M` with `M = 1.5 · 2⁵²` (exact for `|q| < 2⁵¹`, ties to even): `f64::round`
    /// is a software routine on baseline x86-64, and its three calls per candidate pair were
    /// a third of all the fluid's instructions.
    #[inline(always)]
    fn separation(k: &PairConstants, a: Vec3, b: Vec3) -> Vec3 {
        let r = a - b;
        let Some((l, inv_l)) = k.periodic else {
            return r;
        };
        const M: f64 = 6_755_399_441_055_744.0;
        let nearest = |x: f64| {
            let q = x * inv_l;
            if q.abs() < 2_251_799_813_685_248.0 {
                x - l * ((q + M) - M)
            } else {
                x - l * q.round()
            }
        };
        Vec3::new(nearest(r.x), nearest(r.y), nearest(r.z))
    }

    /// The constants of one evaluation of the pair sum: squared cutoff and switch radii,
    /// `1/(r_c² − r_s²)`, and the periodic box with its inverse.
    fn constants(&self) -> PairConstants {
        let periodic = self.box_length.map(|l| (l, 1.0 / l));
        match self.cutoff {
            Some(c) => {
                let (c2, s2) = (c * c, (self.switch_start * self.switch_start).min(c * c));
                let shifted = self.cutoff_form == CutoffForm::ShiftedForce;
                PairConstants {
                    c2,
                    s2,
                    inv_width: if c2 > s2 && !shifted { 1.0 / (c2 - s2) } else { 0.0 },
                    inv_rc: if shifted { 1.0 / c } else { 0.0 },
                    periodic,
                }
            }
            None => PairConstants {
                c2: f64::INFINITY,
                s2: f64::INFINITY,
                inv_width: 0.0,
                inv_rc: 0.0,
                periodic,
            },
        }
    }

    /// Force on `i` from `j` (spatial), the field of `j` at `i`, and the pair energy, for
    /// separation `r = xᵢ − xⱼ`; `None` beyond the cutoff.
    #[inline(always)]
    fn pair(&self, sw: &PairConstants, r: Vec3, mi: Vec3, mj: Vec3) -> Option<(Vec3, Vec3, f64)> {
        self.kernel(sw, r, mi, mj).map(|(f, bi, _, e)| (f, bi, e))
    }

    /// [`Dipoles::pair`] for both bodies at once: the force on `i` (that on `j` is its
    /// negative), the field of `j` at `i` and the field of `i` at `j`.
    #[inline(always)]
    fn pair_both(&self, sw: &PairConstants, r: Vec3, mi: Vec3, mj: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
        self.kernel(sw, r, mi, mj).map(|(f, bi, bj, _)| (f, bi, bj))
    }

    /// The pair kernel: the force on `i` from `j` (spatial), the field of `j` at `i`, the
    /// field of `i` at `j` (the field formula with `r → −r`, `i ↔ j`, sharing every
    /// intermediate) and the pair energy, for `r = xᵢ − xⱼ`; `None` beyond the cutoff.
    /// Callers that drop a result let the compiler drop its work.
    ///
    /// Forced inline: with the switch it is past the inliner's threshold, and as a call (its
    /// result returned through memory) the fluid ran at 0.37 M body-steps/s instead of
    /// 0.69 M (10⁴ bodies, 2 threads).
    #[inline(always)]
    fn kernel(&self, sw: &PairConstants, r: Vec3, mi: Vec3, mj: Vec3) -> Option<(Vec3, Vec3, Vec3, f64)> {
        let r2 = r.norm_squared();
        if r2 > sw.c2 {
            return None;
        }
        let inv2 = 1.0 / r2;
        let inv = inv2.sqrt();
        let inv3 = inv * inv2;
        let inv5 = inv3 * inv2;
        let (a, b, ab) = (mi.dot(r), mj.dot(r), mi.dot(mj));
        let prod = a * b;
        // Symmetric in (i, j): swapping them and negating r negates the force exactly.
        let force = (r * (ab - 5.0 * prod * inv2) + (mj * a + mi * b)) * (3.0 * inv5);
        let field = (r * (3.0 * b * inv2) - mj) * inv3;
        let field_j = (r * (3.0 * a * inv2) - mi) * inv3;
        let energy = ab * inv3 - 3.0 * prod * inv5;
        // The switch in t = (r² − r_s²)/(r_c² − r_s²) ∈ [0, 1]: S = 1 − t² (3 − 2t) (the form
        // above) and dS/d(r²) = −6 t (1 − t)/(r_c² − r_s²), so −U ∇S = 12 U t (1 − t)/(r_c² − r_s²) r.
        // Straight-line code: about half the pairs within the cutoff lie in the shell, so a
        // branch would be mispredicted often. Inside (t = 0), S = 1 and ∇S = 0 exactly.
        let (s, ds) = if sw.inv_rc > 0.0 {
            // Shifted force: x = r/r_c, S = 1 − x³ (4 − 3x), −U ∇S = 12 U x³ (1 − x)/r² r.
            let x = r2 * inv * sw.inv_rc;
            let x3 = x * x * x;
            (1.0 - x3 * (4.0 - 3.0 * x), 12.0 * energy * x3 * (1.0 - x) * inv2)
        } else {
            let t = (r2 - sw.s2).max(0.0) * sw.inv_width;
            (
                1.0 - t * t * (3.0 - 2.0 * t),
                12.0 * energy * t * (1.0 - t) * sw.inv_width,
            )
        };
        let (force, field, field_j, mut energy) = (force * s + r * ds, field * s, field_j * s, energy * s);
        let mut total = force;
        let s2 = self.sigma * self.sigma * inv2;
        if s2 > 2f64.powf(-1.0 / 3.0) {
            let s6 = s2 * s2 * s2;
            total += r * (24.0 * self.epsilon * (2.0 * s6 * s6 - s6) * inv2);
            energy += 4.0 * self.epsilon * (s6 * s6 - s6) + self.epsilon;
        }
        Some((total, field, field_j, energy))
    }

    /// The force and field on a body at `xi` with dipole `mi` from its neighbours `list`,
    /// summed as the SIMD lanes sum them: pair `k` into accumulator `k mod 4`, combined as
    /// `(a₀ + a₁) + (a₂ + a₃)`; `partner(k, [force on j, field at j])` gets each pair's share
    /// of the partner (zeros beyond the cutoff). The lanes give the same bits.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn lane_sums(
        &self,
        k: &PairConstants,
        xi: Vec3,
        mi: Vec3,
        position: &[Vec3],
        dipoles: &[Vec3],
        list: &[u32],
        mut partner: impl FnMut(usize, [Vec3; 2]),
    ) -> (Vec3, Vec3) {
        let mut f = [Vec3::ZERO; 4];
        let mut b = [Vec3::ZERO; 4];
        for (n, &j) in list.iter().enumerate() {
            let j = j as usize;
            let r = Self::separation(k, xi, position[j]);
            match self.pair_both(k, r, mi, dipoles[j]) {
                Some((fij, bi, bj)) => {
                    f[n % 4] += fij;
                    b[n % 4] += bi;
                    partner(n, [-fij, bj]);
                }
                None => partner(n, [Vec3::ZERO; 2]),
            }
        }
        ((f[0] + f[1]) + (f[2] + f[3]), (b[0] + b[1]) + (b[2] + b[3]))
    }

    /// [`Dipoles::lane_sums`] of the full list: the force and field on the body only.
    fn gather_pairs(
        &self,
        k: &PairConstants,
        xi: Vec3,
        mi: Vec3,
        position: &[Vec3],
        dipoles: &[Vec3],
        list: &[u32],
    ) -> (Vec3, Vec3) {
        self.lane_sums(k, xi, mi, position, dipoles, list, |_, _| {})
    }

    /// [`Dipoles::lane_sums`] of a half list: the partners' shares into `slots`.
    #[allow(clippy::too_many_arguments)]
    fn half_pairs(
        &self,
        k: &PairConstants,
        xi: Vec3,
        mi: Vec3,
        position: &[Vec3],
        dipoles: &[Vec3],
        list: &[u32],
        slots: &mut [[Vec3; 2]],
    ) -> (Vec3, Vec3) {
        self.lane_sums(k, xi, mi, position, dipoles, list, |n, share| slots[n] = share)
    }

    /// The constants of the SIMD pair kernel.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    fn lane_kernel(&self, k: &PairConstants) -> crate::many::lanes::PairKernel {
        crate::many::lanes::PairKernel {
            c2: k.c2,
            s2: k.s2,
            inv_width: k.inv_width,
            inv_rc: k.inv_rc,
            periodic: k.periodic,
            sigma2: self.sigma * self.sigma,
            epsilon: self.epsilon,
            wca: 2f64.powf(-1.0 / 3.0),
        }
    }

    /// Whether the current Verlet list keeps the bodies in cell order
    /// ([`Dipoles::spatial_sort`] with the full list and a cell list).
    #[must_use]
    pub fn spatially_sorted(&self) -> bool {
        let s = self.scratch.lock().expect("not poisoned");
        !s.order.is_empty() && s.order.len() == s.reference.len()
    }

    /// Verlet-list builds so far (the list is rebuilt when a body has moved more than half
    /// the skin).
    #[must_use]
    pub fn list_builds(&self) -> u64 {
        self.scratch.lock().expect("not poisoned").builds
    }

    /// Whether the Verlet list of the last build holds for `c`: the list to be used (half or
    /// full, sorted or not) was built for this many bodies, and no body has moved more than
    /// half the skin since.
    fn list_is_fresh(&self, c: &Configuration<'_>, s: &Scratch) -> bool {
        let n = c.position.len();
        let limit = (0.5 * self.skin) * (0.5 * self.skin);
        s.reference.len() == n
            // The list built is the one to be used (the limit may have changed).
            && if n <= self.half_list_max_bodies {
                s.half.is_built_for(n) && s.list_start.is_empty()
            } else {
                s.list_start.len() == n + 1 && !s.half.is_built_for(n)
            }
            && s.sort_requested == self.spatial_sort
            && c.position
                .iter()
                .zip(&s.reference)
                .all(|(x, x0)| (*x - *x0).norm_squared() <= limit)
    }

    /// Rebuild the Verlet list if it is missing, stale (a body moved more than `skin/2`
    /// since the last build) or for another number of bodies; `true` when there is one.
    fn update_list(&self, c: &Configuration<'_>, s: &mut Scratch) -> bool {
        let Some(cutoff) = self.cutoff else {
            return false;
        };
        let n = c.position.len();
        let half = n <= self.half_list_max_bodies;
        if self.list_is_fresh(c, s) {
            return true;
        }
        let reach = cutoff + self.skin;
        let reach2 = reach * reach;
        let constants = self.constants();
        let mut list_start = std::mem::take(&mut s.list_start);
        let mut list = std::mem::take(&mut s.list);
        list_start.clear();
        list.clear();
        list_start.push(0);
        // In parallel over fixed chunks of bodies, then joined in chunk order: the same list
        // as a sequential build, for any number of threads.
        let chunk = crate::many::CHUNK;
        let mut chunks = std::mem::take(&mut s.chunk_lists);
        chunks.resize_with(n.div_ceil(chunk), Default::default);
        let sort = self.spatial_sort;
        let (mut order, mut rank) = (std::mem::take(&mut s.order), std::mem::take(&mut s.rank));
        {
            let cells = self.build_cells_of(c, s, reach);
            let cells = cells.as_ref();
            order.clear();
            rank.clear();
            if let (true, Some(cells)) = (sort, cells) {
                // The bodies in cell order; the list then names neighbours by their place.
                order.extend(cells.sorted.iter().map(|&i| i as u32));
                rank.resize(n, 0);
                for (k, &i) in order.iter().enumerate() {
                    rank[i as usize] = k as u32;
                }
            }
            let (order, rank) = (&*order, &*rank);
            // Distances to the candidates' images in the stencil cells (no minimum image per
            // candidate) where that image is the nearest one: in a box at least twice the
            // reach, or without a box.
            let images = cells
                .filter(|cl| !cl.periodic || cl.span >= 2.0 * reach)
                .map(|cl| (cl.wrapped, cl.cell_rank));
            let fill = |k: usize, (entries, counts): &mut (Vec<u32>, Vec<u32>)| {
                entries.clear();
                counts.clear();
                for place in k * chunk..((k + 1) * chunk).min(n) {
                    let i = if order.is_empty() { place } else { order[place] as usize };
                    let before = entries.len();
                    let xi = c.position[i];
                    // Body i's wrapped position (its entry in cell order).
                    let xi_wrapped = images.map_or(Vec3::ZERO, |(w, cell_rank)| w[cell_rank[i] as usize]);
                    // Branch-free: every candidate of a run is written, and kept when within
                    // reach (a branch taken by a quarter of the candidates at random was
                    // mispredicted often).
                    self.for_neighbour_runs(i, c, cells, |run, first, offset| {
                        // Written into the spare capacity, every candidate, the count of
                        // kept ones advancing only past those within reach (no resize, which
                        // was a call per run).
                        entries.reserve(run.len());
                        let spare = &mut entries.spare_capacity_mut()[..run.len()];
                        let mut kept = 0;
                        let sorted = !rank.is_empty();
                        let mut keep = |k: usize, j: usize, within: bool| {
                            // With the sort, the place of the body at `first + k` in cell
                            // order is that index itself.
                            let entry = if sorted { first + k } else { j };
                            spare[kept].write(entry as u32);
                            // The half list keeps the pairs this place owns.
                            // (`&`, not `&&`: no branch on the random `within`.)
                            let owned = !half | half_list::owns_pair(place, entry);
                            kept += usize::from(within & (j != i) & owned);
                        };
                        match images {
                            // The candidate's image in this stencil cell, read in cell order:
                            // the nearest one within reach, as the box is at least twice the
                            // reach.
                            Some((w, _)) => {
                                for (k, (&j, wj)) in run.iter().zip(&w[first..first + run.len()]).enumerate() {
                                    keep(k, j, (xi_wrapped - (*wj + offset)).norm_squared() <= reach2);
                                }
                            }
                            None => {
                                for (k, &j) in run.iter().enumerate() {
                                    keep(
                                        k,
                                        j,
                                        Self::separation(&constants, xi, c.position[j]).norm_squared() <= reach2,
                                    );
                                }
                            }
                        }
                        let len = entries.len() + kept;
                        // SAFETY: the first `kept` spare entries were written (each kept
                        // entry was written before the count passed it).
                        unsafe { entries.set_len(len) };
                    });
                    counts.push((entries.len() - before) as u32);
                }
            };
            #[cfg(feature = "parallel")]
            {
                use rayon::prelude::*;
                chunks.par_iter_mut().enumerate().for_each(|(k, ch)| fill(k, ch));
            }
            #[cfg(not(feature = "parallel"))]
            for (k, ch) in chunks.iter_mut().enumerate() {
                fill(k, ch);
            }
        }
        s.order = order;
        s.rank = rank;
        s.sort_requested = sort;
        // The half list and its partitions' windows, or the full list, joined in chunk order.
        if half {
            s.half.build(n, &chunks);
            list_start.clear();
        } else {
            s.half.clear();
            for (entries, counts) in &chunks {
                for &count in counts {
                    list_start.push(list_start[list_start.len() - 1] + count as usize);
                }
                list.extend_from_slice(entries);
            }
        }
        s.chunk_lists = chunks;
        s.list_start = list_start;
        s.list = list;
        s.reference.clear();
        s.reference.extend_from_slice(c.position);
        s.builds += 1;
        true
    }

    fn build_cells<'a>(&self, c: &Configuration<'_>, s: &'a mut Scratch) -> Option<Cells<'a>> {
        let cutoff = self.cutoff?;
        self.build_cells_of(c, s, cutoff)
    }

    /// A cell list whose stencil reaches every body within `cutoff`.
    fn build_cells_of<'a>(&self, c: &Configuration<'_>, s: &'a mut Scratch, cutoff: f64) -> Option<Cells<'a>> {
        let n_bodies = c.position.len();
        let (origin, extent, periodic) = match self.box_length {
            Some(l) => (Vec3::ZERO, Vec3::new(l, l, l), true),
            None => {
                let mut lo = Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
                let mut hi = -lo;
                for p in c.position {
                    lo = Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
                    hi = Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
                }
                (lo, hi - lo, false)
            }
        };
        // Cells at least half the cutoff wide with a stencil of 5 a side (in a periodic box
        // at least 5 cells a side), else at least the cutoff wide with a stencil of 3; at
        // most 64 a side. The finer cells cover a smaller volume: at 10³ bodies (box 14.9,
        // reach 3.3) 125 of 9³ cells instead of 27 of 4³, 2.5 times fewer candidates.
        let (size, reach) = if periodic {
            let fine = (2.0 * extent.x / cutoff).floor() as usize;
            let coarse = (extent.x / cutoff).floor() as usize;
            if fine >= 5 {
                (extent.x / fine.min(64) as f64, 2)
            } else if coarse >= 3 {
                (extent.x / coarse.min(64) as f64, 1)
            } else {
                return None;
            }
        } else {
            ((0.5 * cutoff).max(extent.max_abs() / 64.0), 2)
        };
        let count = |e: f64| ((e / size).floor() as usize).clamp(1, 64);
        let n = if periodic {
            let k = (extent.x / size).round() as usize;
            [k, k, k]
        } else {
            [count(extent.x), count(extent.y), count(extent.z)]
        };
        let ncells = n[0] * n[1] * n[2];
        let cell = |p: Vec3| {
            let q = p - origin;
            let idx = |v: f64, k: usize| {
                let v = if periodic {
                    v - (v / (k as f64 * size)).floor() * (k as f64 * size)
                } else {
                    v
                };
                ((v / size) as usize).min(k - 1)
            };
            (idx(q.z, n[2]) * n[1] + idx(q.y, n[1])) * n[0] + idx(q.x, n[0])
        };
        s.cell_of.clear();
        s.cell_of.extend(c.position.iter().map(|&p| cell(p)));
        s.cell_start.clear();
        s.cell_start.resize(ncells + 1, 0);
        for &k in &s.cell_of {
            s.cell_start[k + 1] += 1;
        }
        for k in 0..ncells {
            s.cell_start[k + 1] += s.cell_start[k];
        }
        s.sorted.clear();
        s.sorted.resize(n_bodies, 0);
        s.fill.clear();
        s.fill.extend_from_slice(&s.cell_start);
        for (i, &k) in s.cell_of.iter().enumerate() {
            s.sorted[s.fill[k]] = i;
            s.fill[k] += 1;
        }
        s.cell_rank.clear();
        s.cell_rank.resize(n_bodies, 0);
        for (k, &i) in s.sorted.iter().enumerate() {
            s.cell_rank[i] = k as u32;
        }
        let span = n[0] as f64 * size;
        s.wrapped.clear();
        s.wrapped.extend(s.sorted.iter().map(|&i| {
            let p = c.position[i];
            if periodic {
                let wrap = |v: f64| v - (v / span).floor() * span;
                Vec3::new(wrap(p.x), wrap(p.y), wrap(p.z))
            } else {
                p
            }
        }));
        Some(Cells {
            n,
            origin,
            size,
            reach,
            periodic,
            span,
            wrapped: &s.wrapped,
            cell_rank: &s.cell_rank,
            start: &s.cell_start,
            sorted: &s.sorted,
        })
    }

    /// Visit the neighbours `j ≠ i` of `i` in a fixed order.
    fn for_neighbours(&self, i: usize, c: &Configuration<'_>, cells: Option<&Cells<'_>>, mut f: impl FnMut(usize)) {
        self.for_neighbour_runs(i, c, cells, |run, _, _| {
            for &j in run {
                if j != i {
                    f(j);
                }
            }
        });
    }

    /// Visit the candidate neighbours of `i` as runs of bodies, in a fixed order: the bodies
    /// of the stencil's cells (all bodies without a cell list), `i` among them, each run
    /// with where it starts in cell order (in [`Cells::sorted`] and [`Cells::wrapped`]; the
    /// first body's index without a cell list) and the offset of its image (zero without a
    /// cell list).
    #[inline(always)]
    fn for_neighbour_runs(
        &self,
        i: usize,
        c: &Configuration<'_>,
        cells: Option<&Cells<'_>>,
        mut f: impl FnMut(&[usize], usize, Vec3),
    ) {
        let Some(cells) = cells else {
            let mut run = [0usize; 64];
            for first in (0..c.position.len()).step_by(run.len()) {
                let len = run.len().min(c.position.len() - first);
                for (k, r) in run[..len].iter_mut().enumerate() {
                    *r = first + k;
                }
                f(&run[..len], first, Vec3::ZERO);
            }
            return;
        };
        let q = c.position[i] - cells.origin;
        let n = cells.n;
        let home = |v: f64, k: usize| {
            let span = k as f64 * cells.size;
            let v = if cells.periodic {
                v - (v / span).floor() * span
            } else {
                v
            };
            ((v / cells.size) as isize).min(k as isize - 1)
        };
        let (cx, cy, cz) = (home(q.x, n[0]), home(q.y, n[1]), home(q.z, n[2]));
        // The stencil's cells along each axis, wrapped once (a periodic box has at least
        // 2w + 1 cells a side) or dropped at an open boundary: computed once per body, not
        // once per cell (`rem_euclid` per cell cost 10 ns per candidate at 10³ bodies).
        let w = cells.reach;
        let axis = |c: isize, k: usize| {
            let k = k as isize;
            // (cell, image offset in boxes) for each stencil cell along the axis.
            let mut out = [(0usize, 0.0f64); 5];
            let mut len = 0;
            for d in -w..=w {
                let v = c + d;
                let (v, image) = if cells.periodic {
                    if v < 0 {
                        (v + k, -1.0)
                    } else if v >= k {
                        (v - k, 1.0)
                    } else {
                        (v, 0.0)
                    }
                } else if v < 0 || v >= k {
                    continue;
                } else {
                    (v, 0.0)
                };
                out[len] = (v as usize, image);
                len += 1;
            }
            (out, len)
        };
        let ((xs, nx), (ys, ny), (zs, nz)) = (axis(cx, n[0]), axis(cy, n[1]), axis(cz, n[2]));
        // Cells of a row that follow each other in x are contiguous in `sorted`: visit the
        // stencil's x cells of a row as at most two runs (two where the box wraps), in the
        // same order as cell by cell, without a loop exit per cell.
        let mut runs = [(0usize, 0usize, 0.0f64); 2];
        let mut n_runs = 0;
        for &(x, image) in &xs[..nx] {
            if n_runs > 0 && runs[n_runs - 1].1 == x {
                runs[n_runs - 1].1 = x + 1;
            } else {
                runs[n_runs] = (x, x + 1, image);
                n_runs += 1;
            }
        }
        let span = cells.span;
        for &(z, oz) in &zs[..nz] {
            for &(y, oy) in &ys[..ny] {
                let row = (z * n[1] + y) * n[0];
                for &(lo, hi, ox) in &runs[..n_runs] {
                    let offset = Vec3::new(ox * span, oy * span, oz * span);
                    let (a, b) = (cells.start[row + lo], cells.start[row + hi]);
                    f(&cells.sorted[a..b], a, offset);
                }
            }
        }
    }
}

/// `Σ f(k)` over `k < items`, each term computed in parallel and the terms added in order:
/// the same bits for any number of threads.
fn sum_in_order(items: usize, f: impl Fn(usize) -> f64 + Sync + Send) -> f64 {
    #[cfg(feature = "parallel")]
    let terms: Vec<f64> = {
        use rayon::prelude::*;
        (0..items).into_par_iter().map(f).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let terms: Vec<f64> = (0..items).map(f).collect();
    terms.iter().sum()
}

/// This step's positions and dipoles in place order (`order[place]` is a body; the
/// identity without the spatial sort), in parallel over chunks of places.
fn gather_places(s: &mut Scratch, position: &[Vec3], dipoles: &[Vec3]) {
    let n = position.len();
    let order = &s.order;
    s.sorted_position.resize(n, Vec3::ZERO);
    s.sorted_dipole.resize(n, Vec3::ZERO);
    let place = |first: usize, x: &mut [Vec3], m: &mut [Vec3]| {
        for (q, (x, m)) in x.iter_mut().zip(m.iter_mut()).enumerate() {
            let i = if order.is_empty() {
                first + q
            } else {
                order[first + q] as usize
            };
            (*x, *m) = (position[i], dipoles[i]);
        }
    };
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        let chunk = crate::many::CHUNK;
        crate::many::contiguous_per_thread(
            s.sorted_position
                .par_chunks_mut(chunk)
                .zip(s.sorted_dipole.par_chunks_mut(chunk))
                .enumerate(),
        )
        .for_each(|(k, (x, m))| place(k * chunk, x, m));
    }
    #[cfg(not(feature = "parallel"))]
    place(0, &mut s.sorted_position, &mut s.sorted_dipole);
}

/// The pair pass of the half list over partitions of owners: what it reads.
struct HalfPass<'a> {
    model: &'a Dipoles,
    constants: &'a PairConstants,
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    lanes: (bool, crate::many::lanes::PairKernel),
    position: &'a [Vec3],
    dipoles: &'a [Vec3],
    half: &'a HalfList,
}

impl<'a> HalfPass<'a> {
    fn new(
        model: &'a Dipoles,
        constants: &'a PairConstants,
        position: &'a [Vec3],
        dipoles: &'a [Vec3],
        half: &'a HalfList,
    ) -> Self {
        HalfPass {
            model,
            constants,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            lanes: (crate::many::lanes::use_avx(), model.lane_kernel(constants)),
            position,
            dipoles,
            half,
        }
    }

    /// Partition `p` of owners: each owner's force and field from the partners it owns
    /// into `own` (the partition's places), the partners' shares added into `window` in
    /// pair order (`share` holds one owner's shares on the way).
    #[cfg_attr(
        not(all(feature = "simd", target_arch = "x86_64")),
        allow(clippy::unnecessary_literal_unwrap)
    )]
    fn partition(&self, p: usize, own: &mut [[Vec3; 2]], window: &mut Vec<[Vec3; 2]>, share: &mut Vec<[Vec3; 2]>) {
        let half = self.half;
        let (position, dipoles) = (self.position, self.dipoles);
        let first = half.owners(p, position.len()).start;
        window.clear();
        window.resize(half.window_len(p), [Vec3::ZERO; 2]);
        for (q, o) in own.iter_mut().enumerate() {
            let i = first + q;
            let range = half.start[i]..half.start[i + 1];
            let partners = &half.partner[range.clone()];
            share.clear();
            share.resize(partners.len(), [Vec3::ZERO; 2]);
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            let lanes = crate::many::lanes::half_pairs_x4(
                self.lanes.0,
                &self.lanes.1,
                position[i],
                dipoles[i],
                position,
                dipoles,
                partners,
                share,
            );
            #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
            let lanes: Option<(Vec3, Vec3)> = None;
            let (fi, bi) = lanes.unwrap_or_else(|| {
                self.model.half_pairs(
                    self.constants,
                    position[i],
                    dipoles[i],
                    position,
                    dipoles,
                    partners,
                    share,
                )
            });
            for (s, &slot) in share.iter().zip(&half.partner_slot[range]) {
                let w = &mut window[slot as usize];
                w[0] += s[0];
                w[1] += s[1];
            }
            *o = [fi, bi];
        }
    }
}

/// A body's force and torque from its force and field `[f, b]`: the torque is
/// `Rᵀ (m × B)` in the body frame.
#[inline]
fn force_and_torque([f, b]: [Vec3; 2], rotation: &Mat3, dipole: Vec3) -> (Vec3, Vec3) {
    (f, rotation.tr_mul_vec(dipole.cross(b)))
}

/// The half-list evaluation of [`Dipoles`] by a team of threads ([`TeamForces`]), on the
/// list of the last build: `prepare` puts each body's position and dipole at its place and
/// checks its displacement against the skin, `pairs` is [`HalfPass::partition`] over the
/// part's partitions, `forces` is [`HalfList::total`] at each body's place: the operations
/// of [`Dipoles::compute`]'s half-list path, so the same bits. The buffers the phases
/// share are taken from the scratch for the team's life.
struct DipoleTeam<'a> {
    model: &'a Dipoles,
    scratch: std::sync::MutexGuard<'a, Scratch>,
    constants: PairConstants,
    limit: f64,
    n: usize,
    /// Taken from the scratch (given back on drop), written by the phases through the
    /// pointers below: positions and dipoles by place, each place's own sums, each
    /// partition's window and share buffer.
    place_position: Vec<Vec3>,
    place_dipole: Vec<Vec3>,
    own: Vec<[Vec3; 2]>,
    windows: Vec<Vec<[Vec3; 2]>>,
    shares: Vec<Vec<[Vec3; 2]>>,
    position_ptr: *mut Vec3,
    dipole_ptr: *mut Vec3,
    own_ptr: *mut [Vec3; 2],
    windows_ptr: *mut Vec<[Vec3; 2]>,
    shares_ptr: *mut Vec<[Vec3; 2]>,
}

// SAFETY: the phases write disjoint entries of the buffers (a part writes its bodies'
// places, and its partitions' sums, windows and shares) and read others' only in a later
// phase, after a barrier (the calling order of `TeamForces`).
unsafe impl Sync for DipoleTeam<'_> {}

impl<'a> DipoleTeam<'a> {
    /// The team on the current list, if the last evaluation used the half list for `n`
    /// bodies (otherwise `None`: the list is missing, or the full list is in use).
    fn new(model: &'a Dipoles, n: usize) -> Option<Self> {
        model.cutoff?;
        let mut scratch = model.scratch.lock().expect("not poisoned");
        let s = &mut *scratch;
        let parts = s.half.partitions();
        let ready = n > 0
            && n <= model.half_list_max_bodies
            && s.reference.len() == n
            && s.half.is_built_for(n)
            && s.sort_requested == model.spatial_sort
            && (s.rank.is_empty() || s.rank.len() == n)
            && s.sorted_position.len() == n
            && s.sorted_dipole.len() == n
            && s.own.len() == n
            && s.windows.len() == parts
            && s.shares.len() == parts;
        if !ready {
            return None;
        }
        let (mut place_position, mut place_dipole, mut own, mut windows, mut shares) = (
            std::mem::take(&mut s.sorted_position),
            std::mem::take(&mut s.sorted_dipole),
            std::mem::take(&mut s.own),
            std::mem::take(&mut s.windows),
            std::mem::take(&mut s.shares),
        );
        let (position_ptr, dipole_ptr, own_ptr, windows_ptr, shares_ptr) = (
            place_position.as_mut_ptr(),
            place_dipole.as_mut_ptr(),
            own.as_mut_ptr(),
            windows.as_mut_ptr(),
            shares.as_mut_ptr(),
        );
        Some(DipoleTeam {
            model,
            scratch,
            constants: model.constants(),
            limit: (0.5 * model.skin) * (0.5 * model.skin),
            n,
            place_position,
            place_dipole,
            own,
            windows,
            shares,
            position_ptr,
            dipole_ptr,
            own_ptr,
            windows_ptr,
            shares_ptr,
        })
    }

    /// The place of body `i`.
    #[inline]
    fn place(&self, i: usize) -> usize {
        let rank = &self.scratch.rank;
        if rank.is_empty() {
            i
        } else {
            rank[i] as usize
        }
    }
}

impl Drop for DipoleTeam<'_> {
    fn drop(&mut self) {
        let s = &mut *self.scratch;
        s.sorted_position = std::mem::take(&mut self.place_position);
        s.sorted_dipole = std::mem::take(&mut self.place_dipole);
        s.own = std::mem::take(&mut self.own);
        s.windows = std::mem::take(&mut self.windows);
        s.shares = std::mem::take(&mut self.shares);
    }
}

impl TeamForces for DipoleTeam<'_> {
    unsafe fn prepare(&self, first: usize, run: Configuration<'_>) -> bool {
        let len = run.position.len();
        assert!(first + len <= self.n);
        let reference = &self.scratch.reference[first..first + len];
        let mut fresh = true;
        for (q, x0) in reference.iter().enumerate() {
            let p = self.place(first + q);
            assert!(p < self.n);
            // SAFETY: the places of this part's bodies are written by it alone, and read by
            // nobody, in this phase.
            unsafe {
                *self.position_ptr.add(p) = run.position[q];
                *self.dipole_ptr.add(p) = run.rotation[q] * self.model.moment;
            }
            fresh &= (run.position[q] - *x0).norm_squared() <= self.limit;
        }
        fresh
    }

    fn pair_items(&self) -> usize {
        self.scratch.half.partitions()
    }

    unsafe fn pairs(&self, items: std::ops::Range<usize>, config: Configuration<'_>) {
        let half = &self.scratch.half;
        assert!(config.position.len() == self.n && items.end <= half.partitions());
        // SAFETY: no position or dipole is written in this phase.
        let (position, dipoles) = unsafe {
            (
                std::slice::from_raw_parts(self.position_ptr, self.n),
                std::slice::from_raw_parts(self.dipole_ptr, self.n),
            )
        };
        let pass = HalfPass::new(self.model, &self.constants, position, dipoles, half);
        for p in items {
            let owners = half.owners(p, self.n);
            // SAFETY: partition `p`'s sums, window and shares are this part's alone in this
            // phase.
            let (own, window, share) = unsafe {
                (
                    std::slice::from_raw_parts_mut(self.own_ptr.add(owners.start), owners.len()),
                    &mut *self.windows_ptr.add(p),
                    &mut *self.shares_ptr.add(p),
                )
            };
            pass.partition(p, own, window, share);
        }
    }

    unsafe fn forces(&self, first: usize, run: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        let len = run.position.len();
        assert!(first + len <= self.n && force.len() == len && torque.len() == len);
        let half = &self.scratch.half;
        let window = |p: usize| -> &[[Vec3; 2]] {
            assert!(p < half.partitions());
            // SAFETY: windows are not written in this phase.
            unsafe { (*self.windows_ptr.add(p)).as_slice() }
        };
        for q in 0..len {
            let p = self.place(first + q);
            assert!(p < self.n);
            // SAFETY: sums and dipoles are not written in this phase.
            let (own, dipole) = unsafe { (*self.own_ptr.add(p), *self.dipole_ptr.add(p)) };
            (force[q], torque[q]) = force_and_torque(half.total(p, own, window), &run.rotation[q], dipole);
        }
    }
}

impl Interaction for Dipoles {
    fn compute(&self, c: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        let mut guard = self.scratch.lock().expect("not poisoned");
        let s = &mut *guard;
        s.dipoles.clear();
        s.dipoles.extend(c.rotation.iter().map(|r: &Mat3| *r * self.moment));
        let dipoles = std::mem::take(&mut s.dipoles);
        let constants = self.constants();
        if self.update_list(&c, s) && c.position.len() > self.half_list_max_bodies {
            // Above `half_list_max_bodies` (not by default): every body gathers its own
            // neighbours (each pair twice).
            // With the spatial sort, the list names places in cell order: gather this step's
            // positions and dipoles into that order once, so that the pair loop reads memory
            // near each body (the same values, so the same bits).
            let sorted = s.order.len() == c.position.len();
            if sorted {
                gather_places(s, c.position, &dipoles);
            }
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            let (avx, lane_kernel) = (crate::many::lanes::use_avx(), self.lane_kernel(&constants));
            // The force and field on the body at place `k` (its neighbours' places in `list`).
            let body = |k: usize, xi: Vec3, mi: Vec3, position: &[Vec3], dipole: &[Vec3]| -> (Vec3, Vec3) {
                let neighbours = &s.list[s.list_start[k]..s.list_start[k + 1]];
                #[cfg(all(feature = "simd", target_arch = "x86_64"))]
                let lanes =
                    crate::many::lanes::gather_pairs_x4(avx, &lane_kernel, xi, mi, position, dipole, neighbours);
                #[cfg(all(feature = "simd", target_arch = "x86_64"))]
                let sums = lanes.unwrap_or_else(|| self.gather_pairs(&constants, xi, mi, position, dipole, neighbours));
                #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
                let sums = self.gather_pairs(&constants, xi, mi, position, dipole, neighbours);
                sums
            };
            if sorted {
                // In cell order, so that consecutive bodies share neighbours in cache; then
                // each body takes its sums from its place.
                let n = c.position.len();
                let mut sums = std::mem::take(&mut s.sorted_sums);
                sums.resize(n, [Vec3::ZERO; 2]);
                let (x, m) = (&s.sorted_position, &s.sorted_dipole);
                let place_sums = |first: usize, out: &mut [[Vec3; 2]]| {
                    for (q, o) in out.iter_mut().enumerate() {
                        let k = first + q;
                        let (f, b) = body(k, x[k], m[k], x, m);
                        *o = [f, b];
                    }
                };
                #[cfg(feature = "parallel")]
                {
                    use rayon::prelude::*;
                    let chunk = crate::many::CHUNK;
                    crate::many::contiguous_per_thread(sums.par_chunks_mut(chunk).enumerate())
                        .for_each(|(k, out)| place_sums(k * chunk, out));
                }
                #[cfg(not(feature = "parallel"))]
                place_sums(0, &mut sums);
                let rank = &s.rank;
                for_chunks(force, torque, |i, f, t| {
                    let [fi, bi] = sums[rank[i] as usize];
                    *f = fi;
                    *t = c.rotation[i].tr_mul_vec(dipoles[i].cross(bi));
                });
                s.sorted_sums = sums;
            } else {
                for_chunks(force, torque, |i, f, t| {
                    let mi = dipoles[i];
                    let (fi, bi) = body(i, c.position[i], mi, c.position, &dipoles);
                    *f = fi;
                    *t = c.rotation[i].tr_mul_vec(mi.cross(bi));
                });
            }
            s.dipoles = dipoles;
            return;
        }
        if !s.reference.is_empty() && s.reference.len() == c.position.len() && self.cutoff.is_some() {
            // Each pair once (Newton's third law), partition by partition of owners, each
            // owner over its partners in lanes (the force and field on the owner summed as
            // the gather sums them), the partners' shares into the partition's window; then
            // every body adds the windows covering its place, in partition order
            // (`HalfList`). Nothing depends on the thread count. With the spatial sort
            // the list, the sums and the windows are in places (cell order), so that a
            // partition's partners are few chunks of places, near it.
            let n = c.position.len();
            gather_places(s, c.position, &dipoles);
            s.own.resize(n, [Vec3::ZERO; 2]);
            let parts = s.half.partitions();
            s.windows.resize_with(parts, Vec::new);
            s.shares.resize_with(parts, Vec::new);
            let pass = HalfPass::new(self, &constants, &s.sorted_position, &s.sorted_dipole, &s.half);
            let per = s.half.partition_places;
            #[cfg(feature = "parallel")]
            {
                use rayon::prelude::*;
                crate::many::contiguous_per_thread(
                    s.own
                        .par_chunks_mut(per)
                        .zip(s.windows.par_iter_mut())
                        .zip(s.shares.par_iter_mut())
                        .enumerate(),
                )
                .for_each(|(p, ((own, window), share))| pass.partition(p, own, window, share));
            }
            #[cfg(not(feature = "parallel"))]
            for (p, ((own, window), share)) in s
                .own
                .chunks_mut(per)
                .zip(s.windows.iter_mut())
                .zip(s.shares.iter_mut())
                .enumerate()
            {
                pass.partition(p, own, window, share);
            }
            let (half, own, windows, rank) = (&s.half, &s.own, &s.windows, &s.rank);
            for_chunks(force, torque, |i, f, t| {
                let p = if rank.is_empty() { i } else { rank[i] as usize };
                let total = half.total(p, own[p], |k| windows[k].as_slice());
                (*f, *t) = force_and_torque(total, &c.rotation[i], dipoles[i]);
            });
            s.dipoles = dipoles;
            return;
        }
        let cells = self.build_cells(&c, s);
        for_chunks(force, torque, |i, f, t| {
            let mi = dipoles[i];
            let (mut fi, mut bi) = (Vec3::ZERO, Vec3::ZERO);
            self.for_neighbours(i, &c, cells.as_ref(), |j| {
                let r = Self::separation(&constants, c.position[i], c.position[j]);
                if let Some((fij, field, _)) = self.pair(&constants, r, mi, dipoles[j]) {
                    fi += fij;
                    bi += field;
                }
            });
            *f = fi;
            *t = c.rotation[i].tr_mul_vec(mi.cross(bi));
        });
        s.dipoles = dipoles;
    }

    fn team_forces(&self, bodies: usize, team: &mut dyn FnMut(&dyn TeamForces)) -> bool {
        match DipoleTeam::new(self, bodies) {
            Some(t) => {
                team(&t);
                true
            }
            None => false,
        }
    }

    fn potential_energy(&self, c: Configuration<'_>) -> f64 {
        let dipoles: Vec<Vec3> = c.rotation.iter().map(|r| *r * self.moment).collect();
        let mut guard = self.scratch.lock().expect("not poisoned");
        let constants = self.constants();
        let n = c.position.len();
        let pair_energy = |i: usize, j: usize| {
            let r = Self::separation(&constants, c.position[i], c.position[j]);
            self.pair(&constants, r, dipoles[i], dipoles[j])
                .map_or(0.0, |(_, _, e)| e)
        };
        if self.cutoff.is_some() && n > 0 && self.list_is_fresh(&c, &guard) && guard.half.is_built_for(n) {
            // The half list holds every pair within the cutoff: each pair once, partition
            // by partition in parallel, the partitions' sums added in order (the same bits
            // for any number of threads; the cell sum below adds the same terms in another
            // order, equal to round-off). Five times fewer candidates than the cells.
            let s = &*guard;
            let place = |q: usize| if s.order.is_empty() { q } else { s.order[q] as usize };
            let half = &s.half;
            return sum_in_order(half.partitions(), |p| {
                let mut energy = 0.0;
                for o in half.owners(p, n) {
                    let i = place(o);
                    for &j in &half.partner[half.start[o]..half.start[o + 1]] {
                        energy += pair_energy(i, place(j as usize));
                    }
                }
                energy
            });
        }
        let cells = self.build_cells(&c, &mut guard);
        // Each pair once (j > i), summed body by body within fixed chunks of bodies, in
        // parallel, and the chunks' sums added in chunk order: the same bits for any number
        // of threads.
        let chunk = crate::many::CHUNK;
        let cells = cells.as_ref();
        sum_in_order(n.div_ceil(chunk), |k| {
            let mut energy = 0.0;
            for i in k * chunk..((k + 1) * chunk).min(n) {
                self.for_neighbours(i, &c, cells, |j| {
                    if j > i {
                        energy += pair_energy(i, j);
                    }
                });
            }
            energy
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Rng;

    #[test]
    fn minimum_image_matches_rounding_of_the_quotient() {
        let mut rng = Rng::new(3);
        for l in [1.0, 9.1, 6.0, 1e-3, 1e5] {
            let model = Dipoles::new(Vec3::ZERO, 1.0, 1.0, Some(0.5 * l), Some(l)).unwrap();
            let k = model.constants();
            for _ in 0..10_000 {
                // Separations of up to 40 boxes, and far beyond 2⁵¹ boxes (the fallback).
                let scale = if rng.uniform() < 0.1 { 1e17 * l } else { 40.0 * l };
                let a = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * scale;
                let b = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * l;
                let r = Dipoles::separation(&k, a, b);
                let d = a - b;
                let reference = |x: f64| x - l * (x / l).round();
                let expected = Vec3::new(reference(d.x), reference(d.y), reference(d.z));
                // Both pick the nearest image; they could differ only at |r_i| = L/2 exactly.
                // (Beyond 2⁵¹ boxes the separation itself is not resolved to within a box.)
                if scale < 100.0 * l {
                    assert!(r.max_abs() <= 0.5 * l * (1.0 + 1e-15), "{r:?} for L = {l}");
                }
                assert!(
                    (r - expected).max_abs() <= 1e-15 * scale.max(l),
                    "{r:?} vs {expected:?}"
                );
            }
        }
        let open = Dipoles::new(Vec3::ZERO, 1.0, 1.0, Some(3.0), None).unwrap();
        let a = Vec3::new(10.0, -20.0, 30.0);
        assert_eq!(Dipoles::separation(&open.constants(), a, Vec3::ZERO), a);
    }

    /// The SIMD pair gather gives the scalar sum's bits: periodic and open boxes, pairs in
    /// the WCA range, in the switch shell and beyond the cutoff, lists of every length mod 4.
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    #[test]
    fn simd_pair_gather_equals_the_scalar_sum_bit_for_bit() {
        if !crate::many::lanes::use_avx() {
            eprintln!("no AVX on this processor: the lanes are never used");
            return;
        }
        let mut rng = Rng::new(17);
        for (box_length, cutoff, form) in [
            (Some(9.0), 3.0, CutoffForm::Switched),
            (None, 2.5, CutoffForm::Switched),
            (Some(9.0), 3.0, CutoffForm::ShiftedForce),
        ] {
            let mut model = Dipoles::new(Vec3::new(0.0, 0.0, 1.0), 1.0, 1.0, Some(cutoff), box_length).unwrap();
            model.cutoff_form = form;
            let k = model.constants();
            let lanes = model.lane_kernel(&k);
            let side = box_length.unwrap_or(8.0);
            let n = 64;
            let position: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * side)
                .collect();
            let dipoles: Vec<Vec3> = (0..n).map(|_| rng.unit_vector()).collect();
            let (mut taken, mut repelled) = (0, 0);
            for trial in 0..400 {
                let i = trial % n;
                let len = trial % 13;
                let list: Vec<u32> = (0..len)
                    .map(|_| (rng.next_u64() % n as u64) as u32)
                    .filter(|&j| j as usize != i)
                    .collect();
                // Pairs inside the WCA core (r < 2^{1/6} σ), which the lanes evaluate only
                // in groups that hold one.
                repelled += list
                    .iter()
                    .filter(|&&j| Dipoles::separation(&k, position[i], position[j as usize]).norm() < 1.1225)
                    .count();
                let scalar = model.gather_pairs(&k, position[i], dipoles[i], &position, &dipoles, &list);
                if let Some(simd) = crate::many::lanes::gather_pairs_x4(
                    true,
                    &lanes,
                    position[i],
                    dipoles[i],
                    &position,
                    &dipoles,
                    &list,
                ) {
                    taken += 1;
                    for (a, b) in [(simd.0, scalar.0), (simd.1, scalar.1)] {
                        assert_eq!(
                            a.to_array().map(f64::to_bits),
                            b.to_array().map(f64::to_bits),
                            "{a:?} vs {b:?}"
                        );
                    }
                }
            }
            assert_eq!(taken, 400, "the lanes handed over a group");
            assert!(repelled >= 5, "only {repelled} pairs in the WCA core");
        }
    }
}
