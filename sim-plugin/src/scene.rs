//! Scene files: the world as data (TOML, see `docs/world.md`).
//!
//! The thesis's scenes are embedded (`one_block`, the default, and
//! `two_blocks`); [`Scene::load`] accepts either such a name or a path.

use std::path::{Path, PathBuf};

use pushlearn::wire::{BodyName, GHOST_MARKER, MAX_NAME_BYTES};
use pushlearn_core::body::{
    ACTUATOR_ID, ACTUATOR_NAME, BLUE_ID, BLUE_NAME, CYLINDER_ID, CYLINDER_NAME, GROUND_NAME,
    RED_ID, RED_NAME,
};
use serde::{Deserialize, Serialize};

/// Ids the learners key their tables by (`docs/spec/features.md`): these names must
/// carry exactly these ids, and no other body may use them.
pub const KNOWN_IDS: [(&str, u32); 4] = [
    (ACTUATOR_NAME, ACTUATOR_ID),
    (BLUE_NAME, BLUE_ID),
    (RED_NAME, RED_ID),
    (CYLINDER_NAME, CYLINDER_ID),
];

/// The id no body may have: protobuf's default, what a `ModelState` without
/// an id carries, so a learner could not tell such a body from a missing id.
pub const UNSET_ID: u32 = 0;

/// Name of the body the actuator commands drive.
pub const ACTUATOR: &str = ACTUATOR_NAME;

const BUILTINS: [(&str, &str); 3] = [
    ("one_block", include_str!("../scenes/one_block.toml")),
    ("two_blocks", include_str!("../scenes/two_blocks.toml")),
    ("objects", include_str!("../scenes/objects.toml")),
];

// Plausible ranges for a table-top world (see `within`).
const MAX_ACCELERATION: f64 = 1e3;
const MIN_SIZE: f64 = 1e-4;
const MAX_SIZE: f64 = 1e2;
const MIN_MASS: f64 = 1e-6;
const MAX_MASS: f64 = 1e6;
const MIN_INERTIA: f64 = 1e-12;
const MAX_INERTIA: f64 = 1e6;
const MIN_POSITIVE: f64 = f64::MIN_POSITIVE;
const MAX_STIFFNESS: f64 = 1e20;

/// The default scene of every command.
pub const DEFAULT_SCENE: &str = "one_block";

/// The largest scene file read, in bytes. The built-in scenes are under
/// 4 KiB; reading stops here, so `/dev/zero` or a huge file cannot fill
/// memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 20;

/// The most bodies a scene may have. The thesis's worlds have two or three;
/// collision work grows with the square of the count (1600 boxes took 2.9 s
/// a message), and a world that slow serves no one.
pub const MAX_BODIES: usize = 64;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("unknown built-in scene `{0}` (built-ins: one_block, two_blocks, objects)")]
    UnknownBuiltin(String),
    #[error("cannot read scene file {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot read scene file {}: {problem}", path.display())]
    NotAFile { path: PathBuf, problem: String },
    #[error("invalid scene TOML: {0}")]
    Parse(#[from] toml::de::Error),
    #[error("invalid scene: `{field}` {problem}")]
    Invalid { field: String, problem: String },
}

fn invalid(field: impl Into<String>, problem: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        field: field.into(),
        problem: problem.into(),
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub name: String,
    /// World states per simulated second; must divide 1000.
    #[serde(default = "default_publish_rate")]
    pub publish_rate_hz: u32,
    #[serde(default)]
    pub physics: Physics,
    #[serde(default)]
    pub ground: Ground,
    #[serde(default)]
    pub drive: Drive,
    /// Dynamic bodies, in the order they are published.
    #[serde(rename = "body")]
    pub bodies: Vec<BodySpec>,
    /// Friction of chosen pairs of bodies (`[[friction]]`), overriding the
    /// minimum rule for them: a block's friction with the ground and with
    /// the pusher set independently.
    #[serde(rename = "friction", default, skip_serializing_if = "Vec::is_empty")]
    pub frictions: Vec<PairFriction>,
}

/// The friction coefficients of the contacts between two bodies,
/// replacing `min(μ_a, μ_b)` for that pair (softness still comes from the
/// two bodies' `kp` and `kd`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairFriction {
    /// The two bodies by name, in either order; `ground_plane` is the
    /// ground.
    pub between: [String; 2],
    /// Coulomb friction along ODE's first friction direction.
    pub mu1: f64,
    /// Along the second direction; `mu1` when absent (isotropic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu2: Option<f64>,
}

impl PairFriction {
    /// `(mu1, mu2)`, with `mu2` defaulting to `mu1`.
    pub fn coefficients(&self) -> (f64, f64) {
        (self.mu1, self.mu2.unwrap_or(self.mu1))
    }
}

fn default_publish_rate() -> u32 {
    100
}

/// World-level solver settings (Gazebo 2.x defaults, `docs/spec/world.md` §2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Physics {
    pub gravity: [f64; 3],
    /// Must be 0.001 s: publish intervals are counted in 1 ms steps.
    pub step_size: f64,
    pub quickstep_iterations: u32,
    pub sor_w: f64,
    pub erp: f64,
    pub cfm: f64,
    pub contact_max_correcting_vel: f64,
    pub contact_surface_layer: f64,
    pub linear_damping: f64,
    pub angular_damping: f64,
    /// Contact points per colliding geom pair.
    pub max_contacts: u32,
    pub auto_disable: AutoDisable,
}

impl Default for Physics {
    fn default() -> Self {
        let g = ode::StepParams::gazebo();
        Physics {
            gravity: g.gravity,
            step_size: g.step_size,
            quickstep_iterations: g.quickstep_iterations,
            sor_w: g.sor_w,
            erp: g.erp,
            cfm: g.cfm,
            contact_max_correcting_vel: g.contact_max_correcting_vel,
            contact_surface_layer: g.contact_surface_layer,
            linear_damping: g.linear_damping,
            angular_damping: g.angular_damping,
            max_contacts: g.max_contacts_per_pair as u32,
            auto_disable: AutoDisable::default(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AutoDisable {
    pub enabled: bool,
    pub idle_time: f64,
    pub idle_steps: u32,
    pub linear_threshold: f64,
    pub angular_threshold: f64,
}

impl Default for AutoDisable {
    fn default() -> Self {
        let a = ode::StepParams::gazebo().auto_disable;
        AutoDisable {
            enabled: a.enabled,
            idle_time: a.idle_time,
            idle_steps: a.idle_steps,
            linear_threshold: a.linear_threshold,
            angular_threshold: a.angular_threshold,
        }
    }
}

/// The static ground plane z = 0 (stock Gazebo surface).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ground {
    pub mu1: f64,
    pub mu2: f64,
    pub kp: f64,
    pub kd: f64,
}

impl Default for Ground {
    fn default() -> Self {
        Ground {
            mu1: 100.0,
            mu2: 50.0,
            kp: 1e12,
            kd: 1.0,
        }
    }
}

/// How the actuator is driven every step (`docs/spec/world.md` §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Drive {
    /// Height the actuator is held at while moving, m.
    pub z_clamp: f64,
    /// Centre of the movement bound, m.
    pub bound_centre: [f64; 3],
    /// Radius of the movement bound, m.
    pub bound_radius: f64,
    /// Commanded velocities are scaled down to this norm, m/s.
    pub max_speed: f64,
}

impl Default for Drive {
    fn default() -> Self {
        Drive {
            z_clamp: 0.03,
            bound_centre: [0.0, 0.0, 1.0],
            bound_radius: 2.5,
            max_speed: 0.5,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    pub name: String,
    pub id: u32,
    pub shape: ShapeSpec,
    /// kg.
    pub mass: f64,
    /// Diagonal of the body-frame inertia tensor about the shape's centre,
    /// kg·m²; absent, that of a solid of uniform density
    /// ([`BodySpec::inertia_about_centre`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<[f64; 3]>,
    /// The centre of mass in the body frame, from the shape's centre, m;
    /// absent, the shape's centre. The published pose stays the shape's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_of_mass: Option<[f64; 3]>,
    pub mu1: f64,
    pub mu2: f64,
    #[serde(default = "yes")]
    pub gravity: bool,
    pub start: StartPose,
    /// Contact stiffness, N/m.
    #[serde(default = "default_kp")]
    pub kp: f64,
    /// Contact damping, N·s/m.
    #[serde(default = "default_kd")]
    pub kd: f64,
}

fn yes() -> bool {
    true
}
fn default_kp() -> f64 {
    1e12
}
fn default_kd() -> f64 {
    1.0
}

impl BodySpec {
    /// The diagonal of the inertia tensor about the shape's centre: the
    /// file's `inertia`, or else a solid of uniform density of this mass.
    pub fn inertia_about_centre(&self) -> [f64; 3] {
        self.inertia
            .unwrap_or_else(|| self.shape.solid_inertia(self.mass))
    }

    /// The centre of mass from the shape's centre, body frame (zero when the
    /// file gives none).
    pub fn centre_of_mass(&self) -> [f64; 3] {
        self.centre_of_mass.unwrap_or([0.0; 3])
    }

    /// The inertia tensor about the centre of mass, body frame, as its
    /// diagonal and its off-diagonal entries `[xy, xz, yz]` (tensor entries,
    /// `I_xy = −∫ x y dm`). By the parallel-axis theorem the tensor about the
    /// shape's centre is this one plus `m (|c|² E − c cᵀ)`, c the centre of
    /// mass from the centre, so this one is that tensor minus it. Without an
    /// offset it is the file's diagonal untouched.
    pub fn inertia_about_centre_of_mass(&self) -> ([f64; 3], [f64; 3]) {
        let centre = self.inertia_about_centre();
        let c = self.centre_of_mass();
        if c == [0.0; 3] {
            return (centre, [0.0; 3]);
        }
        let m = self.mass;
        let [x, y, z] = c;
        let shift = parallel_axis_shift(m, c);
        (
            [
                centre[0] - shift[0],
                centre[1] - shift[1],
                centre[2] - shift[2],
            ],
            [m * x * y, m * x * z, m * y * z],
        )
    }
}

/// What the parallel-axis theorem adds to the diagonal of an inertia tensor
/// when the axes move from a body's centre of mass to a point `c` away.
pub fn parallel_axis_shift(mass: f64, c: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = c;
    [
        mass * (y * y + z * z),
        mass * (x * x + z * z),
        mass * (x * x + y * y),
    ]
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ShapeSpec {
    Sphere {
        radius: f64,
    },
    /// Full edge lengths along x, y, z.
    Box {
        size: [f64; 3],
    },
    /// Upright: its axis is the body's z axis; `length` is its height.
    Cylinder {
        radius: f64,
        length: f64,
    },
}

impl ShapeSpec {
    /// The diagonal of the inertia tensor of a solid of uniform density
    /// and mass `mass` about its centre, body frame.
    pub fn solid_inertia(&self, mass: f64) -> [f64; 3] {
        match *self {
            ShapeSpec::Sphere { radius } => [0.4 * mass * radius * radius; 3],
            ShapeSpec::Box { size: [a, b, c] } => [
                mass * (b * b + c * c) / 12.0,
                mass * (a * a + c * c) / 12.0,
                mass * (a * a + b * b) / 12.0,
            ],
            ShapeSpec::Cylinder { radius, length } => {
                let across = mass * (3.0 * radius * radius + length * length) / 12.0;
                [across, across, mass * radius * radius / 2.0]
            }
        }
    }

    /// Whether the body-frame point `p` (from the centre) lies strictly
    /// inside the shape.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        let [x, y, z] = p;
        match *self {
            ShapeSpec::Sphere { radius } => x * x + y * y + z * z < radius * radius,
            ShapeSpec::Box { size } => (0..3).all(|k| p[k].abs() < size[k] / 2.0),
            ShapeSpec::Cylinder { radius, length } => {
                x * x + y * y < radius * radius && z.abs() < length / 2.0
            }
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartPose {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    /// Rotation about +z, rad.
    #[serde(default)]
    pub yaw: f64,
}

impl StartPose {
    pub fn position(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// `[x, y, z, w]`.
    pub fn orientation(&self) -> [f64; 4] {
        let h = self.yaw / 2.0;
        [0.0, 0.0, h.sin(), h.cos()]
    }
}

/// The text of the scene file at `path`: a regular file (a FIFO or a
/// device would block or never end) of at most [`MAX_SCENE_FILE_BYTES`].
fn read_scene_file(path: &Path) -> Result<String, SceneError> {
    use std::io::Read;
    let io = |source| SceneError::Io {
        path: path.to_owned(),
        source,
    };
    let refuse = |problem: String| SceneError::NotAFile {
        path: path.to_owned(),
        problem,
    };
    // Checked before opening: opening a FIFO waits for a writer.
    let kind = std::fs::metadata(path).map_err(io)?.file_type();
    if !kind.is_file() {
        use std::os::unix::fs::FileTypeExt;
        let what = if kind.is_dir() {
            "a directory"
        } else if kind.is_fifo() {
            "a FIFO"
        } else if kind.is_char_device() || kind.is_block_device() {
            "a device"
        } else if kind.is_socket() {
            "a socket"
        } else {
            "something else"
        };
        return Err(refuse(format!("it is {what}, not a regular file")));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(MAX_SCENE_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_SCENE_FILE_BYTES {
        return Err(refuse(format!(
            "larger than {MAX_SCENE_FILE_BYTES} bytes, the most a scene file may have"
        )));
    }
    String::from_utf8(bytes).map_err(|_| refuse("not UTF-8 text".to_owned()))
}

impl Scene {
    /// The names of the embedded scenes.
    pub fn builtin_names() -> impl Iterator<Item = &'static str> {
        BUILTINS.iter().map(|(name, _)| *name)
    }

    /// One of the embedded scenes (`one_block`, `two_blocks`).
    pub fn builtin(name: &str) -> Result<Scene, SceneError> {
        let (_, text) = BUILTINS
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| SceneError::UnknownBuiltin(name.to_owned()))?;
        Scene::from_toml_str(text)
    }

    /// A built-in scene by name, otherwise a TOML file at that path.
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        if BUILTINS.iter().any(|(n, _)| *n == name_or_path) {
            return Scene::builtin(name_or_path);
        }
        let path = Path::new(name_or_path);
        if !path.exists() && !name_or_path.contains(['/', '.']) {
            return Err(SceneError::UnknownBuiltin(name_or_path.to_owned()));
        }
        Scene::from_toml_str(&read_scene_file(path)?)
    }

    /// Parses and validates a scene.
    pub fn from_toml_str(text: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text)?;
        scene.validate()?;
        Ok(scene)
    }

    pub fn to_toml_string(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }

    /// Index of the body named `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// The solver settings in the `ode` crate's form.
    pub fn step_params(&self) -> ode::StepParams {
        let p = &self.physics;
        let a = &p.auto_disable;
        ode::StepParams {
            step_size: p.step_size,
            gravity: p.gravity,
            quickstep_iterations: p.quickstep_iterations,
            sor_w: p.sor_w,
            erp: p.erp,
            cfm: p.cfm,
            contact_max_correcting_vel: p.contact_max_correcting_vel,
            contact_surface_layer: p.contact_surface_layer,
            linear_damping: p.linear_damping,
            angular_damping: p.angular_damping,
            max_contacts_per_pair: p.max_contacts as usize,
            auto_disable: ode::AutoDisable {
                enabled: a.enabled,
                linear_threshold: a.linear_threshold,
                angular_threshold: a.angular_threshold,
                idle_time: a.idle_time,
                idle_steps: a.idle_steps,
                average_samples: 1,
            },
        }
    }

    /// Checks everything a world needs beyond the file's syntax.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.bodies.len() > MAX_BODIES {
            return Err(invalid(
                "body",
                format!(
                    "has {} entries; a scene has at most {MAX_BODIES} bodies",
                    self.bodies.len()
                ),
            ));
        }
        if self.name.trim().is_empty() {
            return Err(invalid("name", "must not be empty"));
        }
        if self.publish_rate_hz == 0 || 1000 % self.publish_rate_hz != 0 {
            return Err(invalid(
                "publish_rate_hz",
                format!("must divide 1000, got {}", self.publish_rate_hz),
            ));
        }
        if self.physics.step_size != 0.001 {
            return Err(invalid(
                "physics.step_size",
                format!(
                    "must be 0.001 (publish intervals count 1 ms steps), got {}",
                    self.physics.step_size
                ),
            ));
        }
        self.step_params()
            .validate()
            .map_err(|e| invalid("physics", e.to_string()))?;
        for g in self.physics.gravity {
            within("physics.gravity", g, -MAX_ACCELERATION, MAX_ACCELERATION)?;
        }
        for (f, v) in [
            ("ground.mu1", self.ground.mu1),
            ("ground.mu2", self.ground.mu2),
        ] {
            non_negative(f, v)?;
        }
        within("ground.kp", self.ground.kp, MIN_POSITIVE, MAX_STIFFNESS)?;
        non_negative("ground.kd", self.ground.kd)?;
        let d = &self.drive;
        finite("drive.z_clamp", d.z_clamp)?;
        for c in d.bound_centre {
            finite("drive.bound_centre", c)?;
        }
        positive("drive.bound_radius", d.bound_radius)?;
        positive("drive.max_speed", d.max_speed)?;
        if self.bodies.iter().filter(|b| b.name == ACTUATOR).count() != 1 {
            return Err(invalid(
                "body",
                format!("exactly one body must be named `{ACTUATOR}`"),
            ));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            self.validate_body(i, b)?;
        }
        for (i, f) in self.frictions.iter().enumerate() {
            self.validate_friction(i, f)?;
        }
        Ok(())
    }

    fn validate_friction(&self, i: usize, f: &PairFriction) -> Result<(), SceneError> {
        let field = |f: &str| format!("friction[{i}].{f}");
        for name in &f.between {
            if name != GROUND_NAME && self.body_index(name).is_none() {
                return Err(invalid(
                    field("between"),
                    format!(
                        "names `{name}`, which is neither a body of the scene nor `{GROUND_NAME}`"
                    ),
                ));
            }
        }
        let [a, b] = &f.between;
        if a == b {
            return Err(invalid(
                field("between"),
                format!("names `{a}` twice; a pair is two different bodies"),
            ));
        }
        let same = |o: &PairFriction| {
            let [c, d] = &o.between;
            (a == c && b == d) || (a == d && b == c)
        };
        if let Some(j) = self.frictions[..i].iter().position(same) {
            return Err(invalid(
                field("between"),
                format!("`{a}` and `{b}` already have their friction in friction[{j}]"),
            ));
        }
        non_negative(&field("mu1"), f.mu1)?;
        if let Some(mu2) = f.mu2 {
            non_negative(&field("mu2"), mu2)?;
        }
        Ok(())
    }

    fn validate_body(&self, i: usize, b: &BodySpec) -> Result<(), SceneError> {
        let field = |f: &str| format!("body[{i}].{f}");
        if b.name.len() > MAX_NAME_BYTES {
            return Err(invalid(
                field("name"),
                format!("is {} bytes long (at most {MAX_NAME_BYTES})", b.name.len()),
            ));
        }
        if b.name.is_empty() || b.name == GROUND_NAME || BodyName::parse(&b.name).ghost().is_some()
        {
            return Err(invalid(
                field("name"),
                format!(
                    "`{}` is reserved (empty, `{GROUND_NAME}` or containing `{GHOST_MARKER}`)",
                    b.name
                ),
            ));
        }
        if self.bodies[..i].iter().any(|o| o.name == b.name) {
            return Err(invalid(
                field("name"),
                format!("`{}` is used twice", b.name),
            ));
        }
        if let Some(j) = self.bodies[..i].iter().position(|o| o.id == b.id) {
            return Err(invalid(
                field("id"),
                format!(
                    "{} is already the id of body[{j}] (`{}`)",
                    b.id, self.bodies[j].name
                ),
            ));
        }
        if b.id == UNSET_ID {
            return Err(invalid(
                field("id"),
                format!(
                    "{UNSET_ID} is reserved: it is what a state without an id carries; any other free id will do"
                ),
            ));
        }
        for (name, id) in KNOWN_IDS {
            if (b.name == name) != (b.id == id) {
                return Err(invalid(
                    field("id"),
                    format!(
                        "`{name}` must have id {id} and no other body may use it (got `{}` with id {})",
                        b.name, b.id
                    ),
                ));
            }
        }
        match b.shape {
            ShapeSpec::Sphere { radius } => {
                within(&field("shape.radius"), radius, MIN_SIZE, MAX_SIZE)?
            }
            ShapeSpec::Box { size } => {
                for s in size {
                    within(&field("shape.size"), s, MIN_SIZE, MAX_SIZE)?;
                }
            }
            ShapeSpec::Cylinder { radius, length } => {
                within(&field("shape.radius"), radius, MIN_SIZE, MAX_SIZE)?;
                within(&field("shape.length"), length, MIN_SIZE, MAX_SIZE)?;
            }
        }
        within(&field("mass"), b.mass, MIN_MASS, MAX_MASS)?;
        match b.inertia {
            Some(inertia) => {
                for v in inertia {
                    within(&field("inertia"), v, MIN_INERTIA, MAX_INERTIA)?;
                }
            }
            None => {
                for v in b.shape.solid_inertia(b.mass) {
                    if !(MIN_INERTIA..=MAX_INERTIA).contains(&v) {
                        return Err(invalid(
                            field("inertia"),
                            format!(
                                "is absent, and a solid of this shape and mass has a moment of {v} \
                                 kg·m², outside [{MIN_INERTIA:e}, {MAX_INERTIA:e}]; give it"
                            ),
                        ));
                    }
                }
            }
        }
        if let Some(c) = b.centre_of_mass {
            self.validate_centre_of_mass(&field("centre_of_mass"), b, c)?;
        }
        non_negative(&field("mu1"), b.mu1)?;
        non_negative(&field("mu2"), b.mu2)?;
        within(&field("kp"), b.kp, MIN_POSITIVE, MAX_STIFFNESS)?;
        non_negative(&field("kd"), b.kd)?;
        for (f, v) in [
            ("start.x", b.start.x),
            ("start.y", b.start.y),
            ("start.z", b.start.z),
        ] {
            within(
                &field(f),
                v,
                -pushlearn_core::MAX_POSITION,
                pushlearn_core::MAX_POSITION,
            )?;
        }
        finite(&field("start.yaw"), b.start.yaw)?;
        Ok(())
    }
}

impl Scene {
    /// `c` is `b`'s centre of mass (from the shape's centre).
    fn validate_centre_of_mass(
        &self,
        field: &str,
        b: &BodySpec,
        c: [f64; 3],
    ) -> Result<(), SceneError> {
        for v in c {
            finite(field, v)?;
        }
        if b.name == ACTUATOR && c != [0.0; 3] {
            return Err(invalid(
                field,
                "must be the centre for the actuator: the drive moves and clamps its centre",
            ));
        }
        // Strictly inside the shape: a box or an upright cylinder with its
        // centre of mass beyond its base could not rest on it, and a centre
        // of mass outside a convex solid needs mass outside it.
        if !b.shape.contains(c) {
            return Err(invalid(
                field,
                format!(
                    "{c:?} lies outside the body's {}: its centre of mass must be inside it",
                    match b.shape {
                        ShapeSpec::Sphere { .. } => "sphere",
                        ShapeSpec::Box { .. } => "box",
                        ShapeSpec::Cylinder { .. } => "cylinder",
                    }
                ),
            ));
        }
        let (diagonal, products) = b.inertia_about_centre_of_mass();
        if !ode::positive_definite(diagonal, products) || diagonal.iter().any(|&v| v < MIN_INERTIA)
        {
            return Err(invalid(
                field,
                format!(
                    "{c:?} is too far from the centre for the inertia {:?} about it: the inertia \
                     about the centre of mass (parallel-axis theorem) would have diagonal \
                     {diagonal:?} and products {products:?}, not a positive-definite tensor; \
                     give a larger `inertia` or a smaller offset",
                    b.inertia_about_centre()
                ),
            ));
        }
        Ok(())
    }
}

/// Checks that `v` lies in `[lo, hi]`. Scene values far outside what a
/// table-top world can mean are refused: ODE aborts the process (it does not
/// return an error) when such values make its state overflow.
fn within(field: &str, v: f64, lo: f64, hi: f64) -> Result<(), SceneError> {
    finite(field, v)?;
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must lie in [{lo:e}, {hi:e}], got {v}"),
        ))
    }
}

fn finite(field: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, format!("must be a finite number, got {v}")))
    }
}

fn positive(field: &str, v: f64) -> Result<(), SceneError> {
    finite(field, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must be greater than zero, got {v}"),
        ))
    }
}

fn non_negative(field: &str, v: f64) -> Result<(), SceneError> {
    finite(field, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(invalid(field, format!("must not be negative, got {v}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE_BLOCK: &str = include_str!("../scenes/one_block.toml");
    const BLOCK_INERTIA: &str = "inertia = [1.66667e-3, 0.0216667, 0.0216667]";

    fn error(text: &str) -> String {
        match Scene::from_toml_str(text) {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn solid_inertia_of_each_shape() {
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-15);
        let block = ShapeSpec::Box {
            size: [0.5, 0.1, 0.1],
        };
        assert!(close(
            block.solid_inertia(1.0),
            [0.02 / 12.0, 0.26 / 12.0, 0.26 / 12.0]
        ));
        let cylinder = ShapeSpec::Cylinder {
            radius: 0.1,
            length: 0.1,
        };
        assert!(close(
            cylinder.solid_inertia(1.0),
            [0.04 / 12.0, 0.04 / 12.0, 0.005]
        ));
        let sphere = ShapeSpec::Sphere { radius: 0.025 };
        assert!(close(sphere.solid_inertia(10.0), [2.5e-3; 3]));
    }

    #[test]
    fn the_inertia_about_the_centre_of_mass_follows_the_parallel_axis_theorem() {
        let mut scene = Scene::from_toml_str(ONE_BLOCK).unwrap();
        let block = &mut scene.bodies[1];
        // Without an offset the file's numbers go to ODE untouched.
        assert_eq!(
            block.inertia_about_centre_of_mass(),
            ([1.66667e-3, 0.0216667, 0.0216667], [0.0; 3])
        );
        // About the centre diag(1e-3, 0.041, 0.041); with c = (0.05, 0.02, 0)
        // and m = 1 the theorem takes m(c_y² + c_z²), m(c_x² + c_z²) and
        // m(c_x² + c_y²) off the diagonal and gives the entry m c_x c_y.
        block.inertia = Some([1e-3, 0.04 + 1e-3, 0.04 + 1e-3]);
        block.centre_of_mass = Some([0.05, 0.02, 0.0]);
        let (d, p) = block.inertia_about_centre_of_mass();
        let want_d = [
            1e-3 - 0.02f64.powi(2),
            0.041 - 0.05f64.powi(2),
            0.041 - 0.0029,
        ];
        for k in 0..3 {
            assert!((d[k] - want_d[k]).abs() < 1e-15, "{d:?}");
        }
        assert!((p[0] - 0.05 * 0.02).abs() < 1e-15 && p[1] == 0.0 && p[2] == 0.0);
        assert!(scene.validate().is_ok());
    }

    #[test]
    fn a_centre_of_mass_lies_inside_the_shape() {
        let b = ShapeSpec::Box {
            size: [0.5, 0.1, 0.1],
        };
        assert!(b.contains([0.249, 0.049, -0.049]));
        assert!(!b.contains([0.25, 0.0, 0.0]));
        let c = ShapeSpec::Cylinder {
            radius: 0.1,
            length: 0.1,
        };
        assert!(c.contains([0.07, 0.07, 0.0]));
        assert!(!c.contains([0.08, 0.08, 0.0]));
        assert!(!ShapeSpec::Sphere { radius: 0.1 }.contains([0.0, 0.0, 0.1]));
    }

    #[test]
    fn bad_new_fields_are_named() {
        let body = |line: &str| ONE_BLOCK.replacen(BLOCK_INERTIA, line, 1);
        let pair = |text: &str| format!("{ONE_BLOCK}\n[[friction]]\n{text}\n");
        let cases = [
            (
                body(&format!("{BLOCK_INERTIA}\ncentre_of_mass = [0.3, 0.0, 0.0]")),
                "`body[1].centre_of_mass` [0.3, 0.0, 0.0] lies outside the body's box",
            ),
            (
                body(&format!("{BLOCK_INERTIA}\ncentre_of_mass = [0.0, 0.0, nan]")),
                "`body[1].centre_of_mass` must be a finite number",
            ),
            (
                body(&format!("{BLOCK_INERTIA}\ncentre_of_mass = [0.2, 0.0, 0.0]")),
                "`body[1].centre_of_mass` [0.2, 0.0, 0.0] is too far from the centre",
            ),
            (
                ONE_BLOCK.replacen(
                    "inertia = [2.5e-4, 2.5e-4, 2.5e-4]",
                    "inertia = [2.5e-4, 2.5e-4, 2.5e-4]\ncentre_of_mass = [0.01, 0.0, 0.0]",
                    1,
                ),
                "`body[0].centre_of_mass` must be the centre for the actuator",
            ),
            (
                body("").replacen("mass = 1.0", "mass = 1e6", 1).replacen(
                    "size = [0.5, 0.1, 0.1]",
                    "size = [50.0, 0.1, 0.1]",
                    1,
                ),
                "`body[1].inertia` is absent, and a solid",
            ),
            (
                pair("between = [\"blockA\", \"ground_plane\"]\nmu1 = -0.3"),
                "`friction[0].mu1` must not be negative",
            ),
            (
                pair("between = [\"blockA\", \"ground_plane\"]\nmu1 = 0.3\nmu2 = inf"),
                "`friction[0].mu2` must be a finite number",
            ),
            (
                pair("between = [\"blockA\", \"table\"]\nmu1 = 0.3"),
                "`friction[0].between` names `table`",
            ),
            (
                pair("between = [\"blockA\", \"blockA\"]\nmu1 = 0.3"),
                "`friction[0].between` names `blockA` twice",
            ),
            (
                pair(
                    "between = [\"blockA\", \"actuator\"]\nmu1 = 0.3\n\n[[friction]]\n\
                     between = [\"actuator\", \"blockA\"]\nmu1 = 0.4",
                ),
                "`friction[1].between` `actuator` and `blockA` already have their friction in friction[0]",
            ),
            (
                pair("between = [\"blockA\"]\nmu1 = 0.3"),
                "invalid scene TOML",
            ),
        ];
        for (text, says) in cases {
            let err = error(&text);
            assert!(err.contains(says), "`{err}` does not say `{says}`");
        }
    }
}
