//! Point dipoles with the WCA repulsion ([`Dipoles`]): the model and its pair kernel
//! (here), the cell and Verlet lists (`neighbours`), the half list's evaluation in phases
//! and by a team of threads (`team`); each pair once through `half_list`.

mod domain;
mod neighbours;
mod team;

pub use domain::DomainForces;

use std::sync::Mutex;

use crate::linalg::{Mat3, Vec3};
use crate::many::half_list::HalfList;
use crate::many::interactions::for_chunks;
use crate::many::{Configuration, Interaction, TeamForces};

use team::{each_partition, force_and_torque, gather_places, sum_in_order, DipoleTeam, HalfPass, PartitionScratch};

/// Point dipoles fixed in the body frames, with the Weeks-Chandler-Andersen repulsion:
///
/// ```text
/// U_dd = (μᵢ·μⱼ)/r³ − 3 (μᵢ·r)(μⱼ·r)/r⁵,   μᵢ = Rᵢ m
/// U_wca = 4ε[(σ/r)¹² − (σ/r)⁶] + ε   for r < 2^{1/6} σ
/// ```
///
/// (Gaussian units). With a cutoff, the pairs within it come from a Verlet list with a
/// skin built from a cell list, each pair evaluated once (Newton's third law) by default;
/// without one, all pairs; optionally in a periodic cubic box (minimum image). The pair
/// force is written symmetrically, so `F_ji = −F_ij` bit for bit and the total momentum is
/// kept to round-off.
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
    /// Keep the bodies' positions and dipoles in cell order (re-sorted at each list build),
    /// so that a body's neighbours are near it in memory (default `true`). With the full
    /// list the results are the same bits either way; the half list then owns and sums its
    /// pairs in places, so the bits differ (not the accuracy).
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
    partitions: Vec<PartitionScratch>,
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
    /// ([`Dipoles::spatial_sort`] and a cell list).
    #[must_use]
    pub fn spatially_sorted(&self) -> bool {
        let s = self.scratch.lock().expect("not poisoned");
        !s.order.is_empty() && s.order.len() == s.reference.len()
    }

    /// The reach of the Verlet list, `r_c + skin` (none without a cutoff).
    #[must_use]
    pub fn reach(&self) -> Option<f64> {
        self.cutoff.map(|c| c + self.skin)
    }

    /// The positions at the last build of the Verlet list, in body order (empty without
    /// one): with them a run can be resumed on the same list (an evaluation at these
    /// positions builds it again, bit for bit), so that the resumed run gives the bits of an
    /// uninterrupted one.
    #[must_use]
    pub fn list_reference(&self) -> Vec<Vec3> {
        self.scratch.lock().expect("not poisoned").reference.clone()
    }

    /// Verlet-list builds so far (the list is rebuilt when a body has moved more than half
    /// the skin).
    #[must_use]
    pub fn list_builds(&self) -> u64 {
        self.scratch.lock().expect("not poisoned").builds
    }
}

/// The body at place `p` (`order` empty: places are the bodies' own indices).
#[inline]
fn body_at(order: &[u32], p: usize) -> usize {
    if order.is_empty() {
        p
    } else {
        order[p] as usize
    }
}

/// The place of body `i` (`rank` empty: places are the bodies' own indices).
#[inline]
fn place_of(rank: &[u32], i: usize) -> usize {
    if rank.is_empty() {
        i
    } else {
        rank[i] as usize
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
        // With a cutoff there is a list for this configuration (fresh or just built); without
        // one, all pairs below.
        let listed = self.update_list(&c, s);
        if listed && c.position.len() > self.half_list_max_bodies {
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
                    (*f, *t) = force_and_torque(sums[rank[i] as usize], &c.rotation[i], dipoles[i]);
                });
                s.sorted_sums = sums;
            } else {
                for_chunks(force, torque, |i, f, t| {
                    let (fi, bi) = body(i, c.position[i], dipoles[i], c.position, &dipoles);
                    (*f, *t) = force_and_torque([fi, bi], &c.rotation[i], dipoles[i]);
                });
            }
            s.dipoles = dipoles;
            return;
        }
        if listed {
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
            s.partitions.resize_with(parts, PartitionScratch::default);
            let pass = HalfPass::new(self, &constants, &s.sorted_position, &s.sorted_dipole, &s.half);
            each_partition(&s.half, 0, &mut s.own, &mut s.partitions, &|p, own, scratch| {
                pass.partition(p, own, scratch)
            });
            let (half, own, partitions, rank) = (&s.half, &s.own, &s.partitions, &s.rank);
            for_chunks(force, torque, |i, f, t| {
                let p = place_of(rank, i);
                let total = half.total(p, own[p], |k| partitions[k].window.as_slice());
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
            (*f, *t) = force_and_torque([fi, bi], &c.rotation[i], mi);
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
            let place = |q: usize| body_at(&s.order, q);
            let half = &s.half;
            return sum_in_order(half.partitions(), |p| {
                let mut energy = 0.0;
                for o in half.owners(p) {
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
