//! The shapes a model file draws (MJCF geoms, URDF visuals): what a viewer shows of a model,
//! not part of its dynamics (the masses come from `<inertial>` or from the geoms' volumes).
//! Each shape is posed in its body's frame (the frame origin of the model file, not the
//! centre of mass) or in the world.
//!
//! A mesh is posed as MuJoCo draws it: MuJoCo recentres a mesh at its centroid and turns it
//! to its principal axes of inertia (`mesh_pos`, `mesh_quat`), and composes that same
//! offset into the geom's frame (`geom_pos`, `geom_quat`), so the two cancel and the file's
//! vertices, scaled, appear posed by the geom's own `pos` and orientation. The shapes here
//! keep the file's coordinates and the geom's frame as written, which draws the same thing
//! without computing the inertial frame (URDF meshes are placed by the visual's `<origin>`,
//! as URDF says).
//!
//! Reference: MuJoCo documentation, XML reference, `geom` (types, `size`, `fromto`, `rgba`,
//! `material`, `group`), `mesh` (`file`, `scale`), `compiler` (`meshdir`, `assetdir`);
//! MuJoCo's compiler, `mjCGeom::Compile` (the mesh offset accumulated into the geom's
//! frame); URDF `<visual>`.

use std::path::PathBuf;

use crate::linalg::{Mat3, Vec3};

/// The geometry of a shape, in its own frame (MuJoCo's conventions: axes along z).
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeKind {
    /// A plane through the origin with normal z: half its extent along x and y (0: unbounded,
    /// drawn as a floor grid).
    Plane {
        /// Half-extents along x and y.
        half: [f64; 2],
    },
    /// A sphere about the origin.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A capsule along z: a cylinder of `half_length` each side of the origin with
    /// hemispherical caps.
    Capsule {
        /// Radius.
        radius: f64,
        /// Half the length of its cylinder.
        half_length: f64,
    },
    /// A cylinder along z.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Half its length.
        half_length: f64,
    },
    /// A box about the origin.
    Box {
        /// Half its edges.
        half: [f64; 3],
    },
    /// An ellipsoid about the origin.
    Ellipsoid {
        /// Its semi-axes.
        radii: [f64; 3],
    },
    /// A triangle mesh from a file, in the file's coordinates times `scale` (read by the
    /// viewer that draws it, with [`Mesh::read`](super::mesh::Mesh::read)).
    Mesh {
        /// The geom's name, else the mesh asset's (MJCF); the link's (URDF).
        name: String,
        /// The file as the model names it.
        file: String,
        /// The file found (recorded among the model's input files), or why none was.
        path: Result<PathBuf, String>,
        /// Scale along each axis of the file's coordinates.
        scale: [f64; 3],
        /// Half the edges of the box drawn in its place when the file gives no mesh: the
        /// geom's `size` when it has three positive values (MJCF), else nothing is drawn.
        half: Option<[f64; 3]>,
    },
}

/// A shape of a model, posed in a body's frame or in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// The body it moves with (index into `Model::bodies`), or `None` for the world.
    pub body: Option<usize>,
    /// The geometry.
    pub kind: ShapeKind,
    /// Its origin in the body's frame (from the frame origin) or in the world.
    pub position: Vec3,
    /// Its attitude in the body's frame or in the world.
    pub rotation: Mat3,
    /// Colour and opacity, each in [0, 1].
    pub rgba: [f32; 4],
    /// MuJoCo's visual group (0 to 5; groups 0, 1 and 2 are shown by default).
    pub group: u8,
    /// How it touches other shapes (`None`: drawn only, as URDF visuals and MJCF geoms
    /// with `contype` and `conaffinity` both 0).
    pub collision: Option<Collides>,
}

/// A shape's contact properties (MJCF `geom`: `contype`, `conaffinity`, `friction`).
#[derive(Clone, Debug, PartialEq)]
pub struct Collides {
    /// The geom's name, for messages (`None` when the file gives none).
    pub name: Option<String>,
    /// MuJoCo's bit masks: two shapes may touch when `contype` of either shares a bit with
    /// `conaffinity` of the other.
    pub contype: u32,
    /// See `contype`.
    pub conaffinity: u32,
    /// The sliding friction coefficient µ (MJCF `friction`'s first value; 0 with
    /// `condim = 1`). A pair takes the larger of its two shapes' values, as MuJoCo does.
    pub friction: f64,
}

impl Collides {
    /// Whether shapes with these properties may touch (MuJoCo's rule).
    #[must_use]
    pub fn pairs_with(&self, other: &Collides) -> bool {
        self.contype & other.conaffinity != 0 || other.contype & self.conaffinity != 0
    }
}

impl Shape {
    /// Shown by default, as MuJoCo shows groups 0, 1 and 2.
    #[must_use]
    pub fn shown_by_default(&self) -> bool {
        self.group <= 2
    }

    /// The same shape posed through `(position, rotation)`: the frame it was posed in, seen
    /// from its parent (a welded body merged into its parent).
    #[must_use]
    pub fn moved(&self, position: Vec3, rotation: &Mat3) -> Shape {
        Shape {
            position: position + *rotation * self.position,
            rotation: *rotation * self.rotation,
            ..self.clone()
        }
    }
}
