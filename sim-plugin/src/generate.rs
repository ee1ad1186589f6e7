//! Objects nobody has seen: scenes drawn from seeded distributions
//! (`pushlearn-sim scene generate`, `docs/world.md` "Generated objects").
//!
//! Every generated scene is the push task's world (`one_block`: its ground,
//! physics, drive and actuator, value for value) with one object in place of
//! the blue block, under the blue block's name and id (`blockA`, 15) and at
//! its start, so that every experiment and learner that pushes the blue block
//! runs it unchanged. Each scene is validated before it is returned, so what
//! [`generate`] gives is a valid scene file.

use std::fmt;

use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::scene::{
    parallel_axis_shift, BodySpec, PairFriction, Scene, SceneError, ShapeSpec, ACTUATOR,
};
use pushlearn_core::body::{BLUE_NAME, GROUND_NAME};

/// Which objects a set draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Set {
    /// Boxes, for training (and tuning) learners.
    Train,
    /// Boxes from another stream than the training set's.
    Test,
    /// Cylinders: the shape family no training or test object belongs to.
    HeldOut,
}

impl Set {
    /// The file-name prefix and the word of the CLI.
    pub fn name(self) -> &'static str {
        match self {
            Set::Train => "train",
            Set::Test => "test",
            Set::HeldOut => "held-out",
        }
    }

    /// Part of every object's generator seed: the three sets draw from
    /// disjoint streams whatever the seed.
    fn stream(self) -> u64 {
        match self {
            Set::Train => 1,
            Set::Test => 2,
            Set::HeldOut => 3,
        }
    }

    /// The shape family of the set's objects.
    pub fn family(self) -> Family {
        match self {
            Set::Train | Set::Test => Family::Box,
            Set::HeldOut => Family::Cylinder,
        }
    }
}

impl fmt::Display for Set {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The shape families the world supports today (spheres roll and are the
/// pusher's shape, so they are no object to push).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    Box,
    Cylinder,
}

/// A closed interval a value is drawn from, uniformly. `lo == hi` fixes the
/// value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
}

impl Range {
    pub const fn new(lo: f64, hi: f64) -> Range {
        Range { lo, hi }
    }

    pub fn contains(&self, v: f64) -> bool {
        (self.lo..=self.hi).contains(&v)
    }

    fn draw(&self, rng: &mut ChaCha8Rng) -> f64 {
        if self.lo == self.hi {
            self.lo
        } else {
            rng.random_range(self.lo..=self.hi)
        }
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}, {}]", self.lo, self.hi)
    }
}

/// The distributions objects are drawn from: every value uniform on its
/// range, each independent of the others. [`Distributions::default`] is the
/// documented one (`docs/world.md` "Generated objects", with sources).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Distributions {
    /// A box's edge across the push (along x), m.
    pub box_width: Range,
    /// A box's edge along the push (along y), m.
    pub box_depth: Range,
    /// A cylinder's radius, m.
    pub cylinder_radius: Range,
    /// Every object's height, m.
    pub height: Range,
    /// kg.
    pub mass: Range,
    /// The centre of mass's horizontal offset from the shape's centre, as a
    /// fraction of the distance to the shape's side in that direction (a
    /// box: each of x and y on its own; a cylinder: the distance from the
    /// axis as a fraction of the radius, at a uniform angle).
    pub com_fraction: Range,
    /// Coulomb friction of the object with the ground (isotropic).
    pub ground_friction: Range,
    /// Coulomb friction of the object with the pusher (isotropic).
    pub pusher_friction: Range,
}

impl Default for Distributions {
    fn default() -> Self {
        Distributions {
            box_width: Range::new(0.1, 0.5),
            box_depth: Range::new(0.1, 0.3),
            cylinder_radius: Range::new(0.05, 0.15),
            height: Range::new(0.06, 0.1),
            mass: Range::new(0.5, 2.0),
            com_fraction: Range::new(-0.5, 0.5),
            ground_friction: Range::new(0.1, 0.3),
            pusher_friction: Range::new(0.1, 0.5),
        }
    }
}

/// The largest centre-of-mass fraction: beyond it the tensor about the
/// centre of mass stops being positive definite for the thinnest boxes
/// (`BodySpec::inertia_about_centre_of_mass`; a box needs f⁴ < 1/9), and the
/// object would need mass at its very rim.
pub const MAX_COM_FRACTION: f64 = 0.5;

/// The largest friction coefficient accepted: far beyond any pushing
/// material pair (the thesis's blocks have 0.9).
pub const MAX_FRICTION: f64 = 10.0;

/// Why objects cannot be drawn: each names the parameter.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    #[error("`{name}` {range} is empty or not finite: it needs finite lo <= hi")]
    EmptyRange { name: &'static str, range: Range },
    #[error("`{name}` {range} must lie in [{lo}, {hi}]: {why}")]
    OutOfBounds {
        name: &'static str,
        range: Range,
        lo: f64,
        hi: f64,
        why: &'static str,
    },
    #[error("`count` must be at least 1")]
    NoObjects,
    #[error(
        "generated object {index} of set {set} is not a valid scene (a generator bug): {source}"
    )]
    Invalid {
        set: Set,
        index: usize,
        source: SceneError,
    },
}

/// One generated object: its scene and the values drawn for it.
#[derive(Debug, Clone, PartialEq)]
pub struct Generated {
    pub scene: Scene,
    pub object: Object,
}

/// The values drawn for one object (what `index.json` lists).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Object {
    pub name: String,
    pub family: Family,
    pub shape: ShapeSpec,
    pub mass: f64,
    pub centre_of_mass: [f64; 3],
    pub ground_friction: f64,
    pub pusher_friction: f64,
}

/// The scene objects are put in.
const BASE_SCENE: &str = "one_block";

impl Object {
    /// The push task's world with this object as its blue block: what
    /// [`generate`] builds for the values drawn, and what an identification
    /// builds for values it tries (`drive::oracle::identify`).
    ///
    /// # Errors
    /// Values that make no valid scene (e.g. a centre of mass that leaves
    /// the inertia indefinite), naming the field.
    pub fn scene(&self) -> Result<Scene, SceneError> {
        let scene = scene_of(&Scene::builtin(BASE_SCENE)?, self);
        scene.validate()?;
        Ok(scene)
    }
}

impl Distributions {
    /// Checks every range against the push task's world (`base`): names the
    /// first bad parameter.
    fn validate(&self, base: &Scene) -> Result<(), GenerateError> {
        let ranges = [
            ("box_width", self.box_width),
            ("box_depth", self.box_depth),
            ("cylinder_radius", self.cylinder_radius),
            ("height", self.height),
            ("mass", self.mass),
            ("com_fraction", self.com_fraction),
            ("ground_friction", self.ground_friction),
            ("pusher_friction", self.pusher_friction),
        ];
        for (name, range) in ranges {
            if !(range.lo.is_finite() && range.hi.is_finite() && range.lo <= range.hi) {
                return Err(GenerateError::EmptyRange { name, range });
            }
        }
        let bounds = |name, range: Range, lo: f64, hi: f64, why| {
            if lo <= range.lo && range.hi <= hi {
                Ok(())
            } else {
                Err(GenerateError::OutOfBounds {
                    name,
                    range,
                    lo,
                    hi,
                    why,
                })
            }
        };
        let (pusher_radius, pusher_height) = pusher(base);
        let blue_start = blue(base).start;
        // The object's near side must stay ahead of the pusher on the start
        // line (y = 0) with 1 cm to spare.
        let reach = 2.0 * (blue_start.y - pusher_radius - 0.01);
        bounds(
            "box_width",
            self.box_width,
            0.02,
            1.0,
            "a box narrower than 2 cm slips past the pusher; wider than 1 m leaves the table",
        )?;
        bounds(
            "box_depth",
            self.box_depth,
            0.02,
            reach,
            "deeper, the box would overlap the pusher's start line",
        )?;
        bounds(
            "cylinder_radius",
            self.cylinder_radius,
            0.01,
            reach / 2.0,
            "larger, the cylinder would overlap the pusher's start line",
        )?;
        // The pusher's top is at z_clamp + radius: a lower object is ridden
        // over, not pushed. Taller than its narrowest base, an object can
        // tip instead of resting on its base while pushed.
        let narrowest = self
            .box_width
            .lo
            .min(self.box_depth.lo)
            .min(2.0 * self.cylinder_radius.lo);
        bounds(
            "height",
            self.height,
            pusher_height,
            narrowest,
            "lower than the pusher's top it is ridden over; taller than its narrowest base \
             (box_width, box_depth, 2 × cylinder_radius) it need not rest on its base",
        )?;
        bounds(
            "mass",
            self.mass,
            0.01,
            100.0,
            "the pusher weighs 10 kg and the drive sets its velocity",
        )?;
        bounds(
            "com_fraction",
            self.com_fraction,
            -MAX_COM_FRACTION,
            MAX_COM_FRACTION,
            "the centre of mass stays well inside the base, so the object rests, and its \
             inertia stays positive definite",
        )?;
        for (name, range) in [
            ("ground_friction", self.ground_friction),
            ("pusher_friction", self.pusher_friction),
        ] {
            bounds(
                name,
                range,
                0.0,
                MAX_FRICTION,
                "a friction coefficient is not negative",
            )?;
        }
        Ok(())
    }
}

/// The pusher's radius and the height of its top (m).
fn pusher(base: &Scene) -> (f64, f64) {
    let radius = base
        .bodies
        .iter()
        .find(|b| b.name == ACTUATOR)
        .map_or(0.025, |b| match b.shape {
            ShapeSpec::Sphere { radius } => radius,
            ShapeSpec::Box { size } => size[0] / 2.0,
            ShapeSpec::Cylinder { radius, .. } => radius,
        });
    (radius, base.drive.z_clamp + radius)
}

/// The base scene's blue block (the body every object replaces).
fn blue(base: &Scene) -> &BodySpec {
    // `one_block` is embedded and has it; a test keeps it so.
    &base.bodies[base.body_index(BLUE_NAME).unwrap_or(1)]
}

/// The generator of object `index` of `set` under `seed`: its own stream,
/// so that object i is the same whatever the count, and the sets never
/// share one.
fn object_rng(seed: u64, set: Set, index: usize) -> ChaCha8Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&set.stream().to_le_bytes());
    key[16..24].copy_from_slice(&(index as u64).to_le_bytes());
    ChaCha8Rng::from_seed(key)
}

/// Draws `count` objects of `set` from `dist` under `seed` and returns their
/// scenes, named `{set}-{index:03}`.
pub fn generate(
    set: Set,
    count: usize,
    seed: u64,
    dist: &Distributions,
) -> Result<Vec<Generated>, GenerateError> {
    if count == 0 {
        return Err(GenerateError::NoObjects);
    }
    let base = Scene::builtin(BASE_SCENE).map_err(|source| GenerateError::Invalid {
        set,
        index: 0,
        source,
    })?;
    dist.validate(&base)?;
    (0..count)
        .map(|index| {
            let mut rng = object_rng(seed, set, index);
            let object = draw(&mut rng, set, index, dist);
            let scene =
                object
                    .scene()
                    .map_err(|source| GenerateError::Invalid { set, index, source })?;
            Ok(Generated { scene, object })
        })
        .collect()
}

/// One object's values, in a fixed order of draws.
fn draw(rng: &mut ChaCha8Rng, set: Set, index: usize, dist: &Distributions) -> Object {
    let family = set.family();
    let height = dist.height.draw(rng);
    let (shape, centre_of_mass) = match family {
        Family::Box => {
            let width = dist.box_width.draw(rng);
            let depth = dist.box_depth.draw(rng);
            let cx = dist.com_fraction.draw(rng) * width / 2.0;
            let cy = dist.com_fraction.draw(rng) * depth / 2.0;
            (
                ShapeSpec::Box {
                    size: [width, depth, height],
                },
                [cx, cy, 0.0],
            )
        }
        Family::Cylinder => {
            let radius = dist.cylinder_radius.draw(rng);
            let r = dist.com_fraction.draw(rng) * radius;
            let angle = rng.random_range(0.0..std::f64::consts::TAU);
            (
                ShapeSpec::Cylinder {
                    radius,
                    length: height,
                },
                [r * angle.cos(), r * angle.sin(), 0.0],
            )
        }
    };
    Object {
        name: format!("{}-{index:03}", set.name()),
        family,
        shape,
        mass: dist.mass.draw(rng),
        centre_of_mass,
        ground_friction: dist.ground_friction.draw(rng),
        pusher_friction: dist.pusher_friction.draw(rng),
    }
}

/// The push task's world with `object` as its blue block.
fn scene_of(base: &Scene, object: &Object) -> Scene {
    let mut scene = base.clone();
    scene.name = object.name.clone();
    let start_y = blue(base).start.y;
    // The object is uniform about its centre of mass (the solid's moments
    // there) with its mass shifted by c: the file gives the inertia about
    // the shape's centre, so add what the parallel-axis theorem takes off
    // (`BodySpec::inertia_about_centre_of_mass`).
    let solid = object.shape.solid_inertia(object.mass);
    let shift = parallel_axis_shift(object.mass, object.centre_of_mass);
    let inertia = [
        solid[0] + shift[0],
        solid[1] + shift[1],
        solid[2] + shift[2],
    ];
    let height = match object.shape {
        ShapeSpec::Box { size } => size[2],
        ShapeSpec::Cylinder { length, .. } => length,
        ShapeSpec::Sphere { radius } => 2.0 * radius,
    };
    let index = base.body_index(BLUE_NAME).unwrap_or(1);
    let block = &mut scene.bodies[index];
    block.shape = object.shape;
    block.mass = object.mass;
    block.inertia = Some(inertia);
    block.centre_of_mass = (object.centre_of_mass != [0.0; 3]).then_some(object.centre_of_mass);
    block.start.y = start_y;
    block.start.z = height / 2.0;
    scene.frictions = vec![
        PairFriction {
            between: [BLUE_NAME.to_owned(), GROUND_NAME.to_owned()],
            mu1: object.ground_friction,
            mu2: None,
        },
        PairFriction {
            between: [BLUE_NAME.to_owned(), ACTUATOR.to_owned()],
            mu1: object.pusher_friction,
            mu2: None,
        },
    ];
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    fn objects(set: Set, count: usize, seed: u64) -> Vec<Generated> {
        generate(set, count, seed, &Distributions::default()).unwrap()
    }

    #[test]
    fn the_same_seed_gives_the_same_objects_and_object_i_ignores_the_count() {
        let a = objects(Set::Train, 5, 7);
        assert_eq!(a, objects(Set::Train, 5, 7));
        assert_eq!(a[..3], objects(Set::Train, 3, 7)[..]);
        assert_ne!(a[0].object.mass, objects(Set::Train, 1, 8)[0].object.mass);
        // Train and test draw from different streams under one seed.
        let test = objects(Set::Test, 5, 7);
        for (x, y) in a.iter().zip(&test) {
            assert_ne!(x.object.mass, y.object.mass);
        }
    }

    #[test]
    fn every_drawn_value_lies_in_its_range() {
        let d = Distributions::default();
        for set in [Set::Train, Set::Test, Set::HeldOut] {
            for g in objects(set, 200, 1) {
                let o = &g.object;
                assert!(d.mass.contains(o.mass));
                assert!(d.ground_friction.contains(o.ground_friction));
                assert!(d.pusher_friction.contains(o.pusher_friction));
                assert!(o.shape.contains(o.centre_of_mass));
                assert_eq!(o.centre_of_mass[2], 0.0);
                match o.shape {
                    ShapeSpec::Box { size: [w, l, h] } => {
                        assert!(d.box_width.contains(w) && d.box_depth.contains(l));
                        assert!(d.height.contains(h));
                        assert!(o.centre_of_mass[0].abs() <= MAX_COM_FRACTION * w / 2.0);
                        assert!(o.centre_of_mass[1].abs() <= MAX_COM_FRACTION * l / 2.0);
                    }
                    ShapeSpec::Cylinder { radius, length } => {
                        assert!(d.cylinder_radius.contains(radius) && d.height.contains(length));
                        let [x, y, _] = o.centre_of_mass;
                        assert!(x.hypot(y) <= MAX_COM_FRACTION * radius + 1e-15);
                    }
                    ShapeSpec::Sphere { .. } => panic!("a sphere was drawn"),
                }
                let b = &g.scene.bodies[g.scene.body_index(BLUE_NAME).unwrap()];
                assert_eq!((b.id, b.start.x, b.start.y), (15, 0.0, 0.25));
                assert!(g.scene.validate().is_ok());
            }
        }
    }

    #[test]
    fn the_held_out_family_is_never_in_training_or_test() {
        for set in [Set::Train, Set::Test] {
            assert!(objects(set, 300, 3)
                .iter()
                .all(|g| g.object.family == Family::Box
                    && matches!(g.object.shape, ShapeSpec::Box { .. })));
        }
        assert!(objects(Set::HeldOut, 50, 3)
            .iter()
            .all(|g| matches!(g.object.shape, ShapeSpec::Cylinder { .. })));
        assert_ne!(Set::HeldOut.family(), Set::Train.family());
    }

    #[test]
    fn generated_scenes_round_trip_through_the_file() {
        for set in [Set::Train, Set::HeldOut] {
            for g in objects(set, 20, 11) {
                let text = g.scene.to_toml_string().unwrap();
                assert_eq!(Scene::from_toml_str(&text).unwrap(), g.scene, "{text}");
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let d = Distributions::default();
        let cases = [
            (
                Distributions {
                    mass: Range::new(2.0, 1.0),
                    ..d.clone()
                },
                "`mass` [2, 1] is empty",
            ),
            (
                Distributions {
                    ground_friction: Range::new(-0.1, 0.3),
                    ..d.clone()
                },
                "`ground_friction` [-0.1, 0.3] must lie in [0, 10]",
            ),
            (
                Distributions {
                    pusher_friction: Range::new(f64::NAN, 0.3),
                    ..d.clone()
                },
                "`pusher_friction` [NaN, 0.3] is empty or not finite",
            ),
            (
                Distributions {
                    height: Range::new(0.01, 0.1),
                    ..d.clone()
                },
                "`height` [0.01, 0.1] must lie in [0.055",
            ),
            (
                Distributions {
                    height: Range::new(0.06, 0.2),
                    ..d.clone()
                },
                "taller than its narrowest base",
            ),
            (
                Distributions {
                    box_depth: Range::new(0.1, 0.5),
                    ..d.clone()
                },
                "`box_depth` [0.1, 0.5] must lie in [0.02, 0.43",
            ),
            (
                Distributions {
                    com_fraction: Range::new(-0.9, 0.5),
                    ..d.clone()
                },
                "`com_fraction`",
            ),
        ];
        for (dist, says) in cases {
            let err = generate(Set::Train, 1, 0, &dist).unwrap_err().to_string();
            assert!(err.contains(says), "`{err}` does not say `{says}`");
        }
        let err = generate(Set::Train, 0, 0, &d).unwrap_err().to_string();
        assert!(err.contains("`count`"), "{err}");
    }
}
