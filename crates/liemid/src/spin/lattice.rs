//! The geometry of a spin system: sites, nearest-neighbour bonds (each pair once), the
//! neighbours of every site, and a colouring of the bonds into matchings (no two bonds of
//! one colour share a site), which the splitting integrator steps colour by colour.

use crate::error::{Error, Result};

/// Which regular lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LatticeKind {
    /// A chain: `size = [n]`.
    Chain,
    /// A square lattice: `size = [nx, ny]`.
    Square,
    /// A simple cubic lattice: `size = [nx, ny, nz]`.
    Cubic,
    /// Any list of sites and bonds ([`Lattice::from_bonds`]).
    Graph,
}

impl LatticeKind {
    /// The name in scenario files.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            LatticeKind::Chain => "chain",
            LatticeKind::Square => "square",
            LatticeKind::Cubic => "cubic",
            LatticeKind::Graph => "graph",
        }
    }

    /// Number of axes.
    #[must_use]
    pub fn dimension(self) -> usize {
        match self {
            LatticeKind::Chain => 1,
            LatticeKind::Square => 2,
            LatticeKind::Cubic | LatticeKind::Graph => 3,
        }
    }
}

/// The largest number of sites (indices are stored as `u32`).
pub const MAX_SITES: usize = u32::MAX as usize;

/// Sites, bonds and their colouring.
#[derive(Clone, Debug)]
pub struct Lattice {
    kind: LatticeKind,
    size: [usize; 3],
    periodic: bool,
    sites: usize,
    /// Bonds sorted by colour.
    bonds: Vec<[u32; 2]>,
    /// `bonds[colour_start[c]..colour_start[c + 1]]` is colour `c`.
    colour_start: Vec<usize>,
    /// Neighbours of site `i`: `neighbours[neighbour_start[i]..neighbour_start[i + 1]]`.
    neighbour_start: Vec<usize>,
    neighbours: Vec<u32>,
}

impl Lattice {
    /// A chain, square or cubic lattice of `size` sites along each axis (site index
    /// `x + nx (y + ny z)`), periodic or open, with nearest-neighbour bonds.
    ///
    /// # Errors
    /// A size of the wrong length for the kind, a zero size, too many sites, or a periodic
    /// axis of 2 sites (its two neighbours would be one site, and the pair counted twice).
    pub fn new(kind: LatticeKind, size: &[usize], periodic: bool) -> Result<Self> {
        let dim = kind.dimension();
        if kind == LatticeKind::Graph || size.len() != dim {
            return Err(Error::InvalidParameter {
                name: "size",
                value: size.len() as f64,
                reason: match kind {
                    LatticeKind::Chain => "a chain takes one size, [n]",
                    LatticeKind::Square => "a square lattice takes two sizes, [nx, ny]",
                    LatticeKind::Cubic => "a cubic lattice takes three sizes, [nx, ny, nz]",
                    LatticeKind::Graph => "a graph is built by Lattice::from_bonds",
                },
            });
        }
        let mut n = [1usize; 3];
        for (axis, &s) in size.iter().enumerate() {
            if s == 0 {
                return Err(Error::InvalidParameter {
                    name: "size",
                    value: 0.0,
                    reason: "every axis needs at least one site",
                });
            }
            if periodic && s == 2 {
                return Err(Error::InvalidParameter {
                    name: "size",
                    value: 2.0,
                    reason: "a periodic axis needs 1 or at least 3 sites (with 2, both neighbours are the same site)",
                });
            }
            n[axis] = s;
        }
        let sites = n[0]
            .checked_mul(n[1])
            .and_then(|s| s.checked_mul(n[2]))
            .filter(|&s| s <= MAX_SITES)
            .ok_or(Error::InvalidParameter {
                name: "size",
                value: (n[0] as f64) * (n[1] as f64) * (n[2] as f64),
                reason: "more than 2^32 - 1 sites",
            })?;
        // Bonds to the +1 neighbour along each axis, by axis, then by the parity of the
        // coordinate along it: the greedy colouring then finds two colours per axis (three
        // for an odd periodic axis, whose wrap bond meets both parities).
        let index = |c: [usize; 3]| (c[0] + n[0] * (c[1] + n[1] * c[2])) as u32;
        let mut bonds = Vec::new();
        for axis in 0..dim {
            if n[axis] == 1 {
                continue;
            }
            for parity in 0..2 {
                for i in 0..sites {
                    let c = [i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])];
                    if c[axis] % 2 != parity {
                        continue;
                    }
                    let mut d = c;
                    if c[axis] + 1 < n[axis] {
                        d[axis] += 1;
                    } else if periodic {
                        d[axis] = 0;
                    } else {
                        continue;
                    }
                    bonds.push([index(c), index(d)]);
                }
            }
        }
        let mut lattice = Self::build(sites, bonds);
        lattice.kind = kind;
        lattice.size = n;
        lattice.periodic = periodic;
        Ok(lattice)
    }

    /// Any graph: `sites` sites and a list of bonds, each pair once.
    ///
    /// # Errors
    /// A bond to a site that does not exist, a bond of a site to itself, or a pair listed
    /// twice.
    pub fn from_bonds(sites: usize, bonds: &[[usize; 2]]) -> Result<Self> {
        if sites > MAX_SITES {
            return Err(Error::InvalidParameter {
                name: "sites",
                value: sites as f64,
                reason: "more than 2^32 - 1 sites",
            });
        }
        let mut seen = std::collections::HashSet::new();
        let mut list = Vec::with_capacity(bonds.len());
        for &[i, j] in bonds {
            if i >= sites || j >= sites {
                return Err(Error::InvalidParameter {
                    name: "bonds",
                    value: i.max(j) as f64,
                    reason: "a bond names a site that does not exist",
                });
            }
            if i == j {
                return Err(Error::InvalidParameter {
                    name: "bonds",
                    value: i as f64,
                    reason: "a bond joins a site to itself",
                });
            }
            if !seen.insert((i.min(j), i.max(j))) {
                return Err(Error::InvalidParameter {
                    name: "bonds",
                    value: i as f64,
                    reason: "a pair of sites is listed twice (each pair counts once)",
                });
            }
            list.push([i as u32, j as u32]);
        }
        let mut lattice = Self::build(sites, list);
        lattice.size = [sites, 1, 1];
        Ok(lattice)
    }

    /// Colour the bonds greedily in the given order (each takes the smallest colour neither
    /// end has yet), sort them by colour, and list every site's neighbours.
    fn build(sites: usize, bonds: Vec<[u32; 2]>) -> Self {
        let mut used: Vec<u64> = vec![0; sites];
        let mut coloured: Vec<(u32, [u32; 2])> = Vec::with_capacity(bonds.len());
        for b in bonds {
            let (i, j) = (b[0] as usize, b[1] as usize);
            let free = !(used[i] | used[j]);
            let colour = free.trailing_zeros();
            used[i] |= 1 << colour;
            used[j] |= 1 << colour;
            coloured.push((colour, b));
        }
        coloured.sort_by_key(|&(c, _)| c);
        let colours = coloured.last().map_or(0, |&(c, _)| c as usize + 1);
        let mut colour_start = vec![0; colours + 1];
        for &(c, _) in &coloured {
            colour_start[c as usize + 1] += 1;
        }
        for c in 0..colours {
            colour_start[c + 1] += colour_start[c];
        }
        let bonds: Vec<[u32; 2]> = coloured.into_iter().map(|(_, b)| b).collect();
        let mut degree = vec![0usize; sites + 1];
        for b in &bonds {
            degree[b[0] as usize + 1] += 1;
            degree[b[1] as usize + 1] += 1;
        }
        for i in 0..sites {
            degree[i + 1] += degree[i];
        }
        let neighbour_start = degree.clone();
        let mut fill = degree;
        let mut neighbours = vec![0u32; 2 * bonds.len()];
        // In site order, so that each field sums its neighbours in a fixed order.
        let mut by_site: Vec<(u32, u32)> = bonds.iter().flat_map(|b| [(b[0], b[1]), (b[1], b[0])]).collect();
        by_site.sort_unstable();
        for (i, j) in by_site {
            neighbours[fill[i as usize]] = j;
            fill[i as usize] += 1;
        }
        Lattice {
            kind: LatticeKind::Graph,
            size: [sites, 1, 1],
            periodic: false,
            sites,
            bonds,
            colour_start,
            neighbour_start,
            neighbours,
        }
    }

    /// The kind of lattice.
    #[must_use]
    pub fn kind(&self) -> LatticeKind {
        self.kind
    }

    /// Sites along each axis (1 for missing axes).
    #[must_use]
    pub fn size(&self) -> [usize; 3] {
        self.size
    }

    /// Whether the lattice wraps around.
    #[must_use]
    pub fn periodic(&self) -> bool {
        self.periodic
    }

    /// Number of sites.
    #[must_use]
    pub fn sites(&self) -> usize {
        self.sites
    }

    /// Every bond once, sorted by colour.
    #[must_use]
    pub fn bonds(&self) -> &[[u32; 2]] {
        &self.bonds
    }

    /// Number of bond colours.
    #[must_use]
    pub fn colours(&self) -> usize {
        self.colour_start.len() - 1
    }

    /// The bonds of colour `c`: a matching (no two share a site).
    #[must_use]
    pub fn colour(&self, c: usize) -> &[[u32; 2]] {
        &self.bonds[self.colour_start[c]..self.colour_start[c + 1]]
    }

    /// The neighbours of site `i`, in increasing order.
    #[must_use]
    pub fn neighbours(&self, i: usize) -> &[u32] {
        &self.neighbours[self.neighbour_start[i]..self.neighbour_start[i + 1]]
    }

    /// Where the neighbours of site `i` start in the list of all sites' neighbours (for
    /// tables with one entry per (site, neighbour)).
    pub(crate) fn neighbour_offset(&self, i: usize) -> usize {
        self.neighbour_start[i]
    }

    /// Where colour `c` starts in [`Lattice::bonds`].
    pub(crate) fn colour_offset(&self, c: usize) -> usize {
        self.colour_start[c]
    }

    /// The unit vector from site `b[0]` to site `b[1]` of a bond of a chain, square or
    /// cubic lattice (across the boundary for a periodic wrap bond); `None` for a graph.
    #[must_use]
    pub fn bond_direction(&self, b: [u32; 2]) -> Option<[f64; 3]> {
        if self.kind == LatticeKind::Graph {
            return None;
        }
        let n = self.size;
        let coords = |i: usize| [i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])];
        let (ci, cj) = (coords(b[0] as usize), coords(b[1] as usize));
        let mut r = [0.0; 3];
        for axis in 0..3 {
            if ci[axis] != cj[axis] {
                r[axis] = if cj[axis] == (ci[axis] + 1) % n[axis] {
                    1.0
                } else {
                    -1.0
                };
            }
        }
        Some(r)
    }
}
