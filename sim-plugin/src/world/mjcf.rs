//! A scene as MuJoCo's MJCF, generated in memory from the same TOML the ODE
//! world is built from (`docs/world.md`, "Two engines": every choice below
//! and its reason).

use std::fmt::Write as _;

use pushlearn_core::GROUND_NAME;

use crate::scene::{Scene, ShapeSpec};

/// Contact softness, `solref = (time constant, damping ratio)`: two 1 ms
/// steps, critically damped. ODE's contacts are all but rigid (kp = 1e12
/// gives an ERP of about 1); two steps is the stiffest MuJoCo keeps stable
/// (its `refsafe` clamps anything shorter).
pub(super) const SOLREF: [f64; 2] = [0.002, 1.0];

/// Contact impedance, `solimp`: MuJoCo's own default, left alone.
pub(super) const SOLIMP: [f64; 5] = [0.9, 0.95, 0.001, 0.5, 2.0];

/// Torsional and rolling friction: MuJoCo's defaults, unused with
/// `condim = 3` (sliding friction only, as in ODE).
const SPIN_AND_ROLL: [f64; 3] = [0.005, 0.0001, 0.0001];

/// Contacts the data has room for per geom (the ground counts): a box on a
/// plane makes 4, box on box up to 8.
const CONTACTS_PER_GEOM: usize = 16;

/// The MJCF of `scene` (validated). Geom ids follow ODE's geom tags: the
/// ground is geom 0, body i's geom is i + 1; every body's free joint, body
/// and geom carry the body's name.
pub(super) fn mjcf(scene: &Scene) -> String {
    let p = &scene.physics;
    let mut x = String::new();
    // Writing into a String cannot fail; `let _` keeps that visible once.
    let _ = writeln!(x, "<mujoco model=\"{}\">", escape(&scene.name));
    // Masses and inertias are the scene's, never computed from geoms. ODE
    // accepts a diagonal no solid can have (A + B < C: the thesis's blockB);
    // MuJoCo refuses it unless told to replace it by the mean of the three
    // (`unphysical_inertia` names such bodies for a warning).
    let _ = writeln!(
        x,
        "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"true\"/>"
    );
    let _ = writeln!(
        x,
        "  <option timestep=\"{}\" gravity=\"{}\" cone=\"elliptic\" integrator=\"Euler\"/>",
        p.step_size,
        join(&p.gravity)
    );
    let contacts = CONTACTS_PER_GEOM * (scene.bodies.len() + 1);
    // Elliptic contacts of dimension 3 take 3 constraint rows each.
    let _ = writeln!(
        x,
        "  <size nconmax=\"{contacts}\" njmax=\"{}\"/>",
        3 * contacts
    );
    let _ = writeln!(x, "  <worldbody>");
    // Collisions come only from the explicit pairs below (contype and
    // conaffinity 0), which carry each pair's friction.
    let _ = writeln!(
        x,
        "    <geom name=\"{GROUND_NAME}\" type=\"plane\" size=\"0 0 1\" contype=\"0\" conaffinity=\"0\"/>"
    );
    for b in &scene.bodies {
        let name = escape(&b.name);
        let [qx, qy, qz, qw] = b.start.orientation();
        let _ = writeln!(
            x,
            "    <body name=\"{name}\" pos=\"{}\" quat=\"{}\">",
            join(&b.start.position()),
            join(&[qw, qx, qy, qz])
        );
        let _ = writeln!(x, "      <freejoint name=\"{name}\"/>");
        // The body's frame is the shape's centre (what is published); the
        // mass sits at the centre of mass with the inertia about it.
        let (diagonal, products) = b.inertia_about_centre_of_mass();
        let inertia = if products == [0.0; 3] {
            format!("diaginertia=\"{}\"", join(&diagonal))
        } else {
            let [d0, d1, d2] = diagonal;
            let [xy, xz, yz] = products;
            format!("fullinertia=\"{}\"", join(&[d0, d1, d2, xy, xz, yz]))
        };
        let _ = writeln!(
            x,
            "      <inertial pos=\"{}\" mass=\"{}\" {inertia}/>",
            join(&b.centre_of_mass()),
            b.mass
        );
        let shape = match b.shape {
            ShapeSpec::Sphere { radius } => format!("type=\"sphere\" size=\"{radius}\""),
            ShapeSpec::Box { size } => {
                format!("type=\"box\" size=\"{}\"", join(&size.map(|s| s / 2.0)))
            }
            ShapeSpec::Cylinder { radius, length } => {
                format!("type=\"cylinder\" size=\"{radius} {}\"", length / 2.0)
            }
        };
        let _ = writeln!(
            x,
            "      <geom name=\"{name}\" {shape} contype=\"0\" conaffinity=\"0\"/>"
        );
        let _ = writeln!(x, "    </body>");
    }
    let _ = writeln!(x, "  </worldbody>");
    let _ = writeln!(x, "  <contact>");
    let names: Vec<&str> = std::iter::once(GROUND_NAME)
        .chain(scene.bodies.iter().map(|b| b.name.as_str()))
        .collect();
    for (a, first) in names.iter().enumerate() {
        for second in &names[a + 1..] {
            let (mu1, mu2) = pair_friction(scene, first, second);
            let _ = writeln!(
                x,
                "    <pair geom1=\"{}\" geom2=\"{}\" condim=\"3\" friction=\"{mu1} {mu2} {}\" solref=\"{}\" solimp=\"{}\"/>",
                escape(first),
                escape(second),
                join(&SPIN_AND_ROLL),
                join(&SOLREF),
                join(&SOLIMP)
            );
        }
    }
    let _ = writeln!(x, "  </contact>");
    let _ = writeln!(x, "</mujoco>");
    x
}

/// The bodies whose inertia about the centre of mass breaks the triangle
/// inequality, which MuJoCo replaces by the mean of its diagonal.
pub(super) fn unphysical_inertia(scene: &Scene) -> impl Iterator<Item = &str> {
    scene.bodies.iter().filter_map(|b| {
        let (d, _) = b.inertia_about_centre_of_mass();
        let broken = (0..3).any(|k| d[k] > d[(k + 1) % 3] + d[(k + 2) % 3]);
        broken.then_some(b.name.as_str())
    })
}

/// The pair's `(mu1, mu2)` by ODE's world's rule: the scene's `[[friction]]`
/// entry for it, else the minimum of the two materials' coefficients.
fn pair_friction(scene: &Scene, a: &str, b: &str) -> (f64, f64) {
    let given = scene.frictions.iter().find(|f| {
        let [c, d] = &f.between;
        (c == a && d == b) || (c == b && d == a)
    });
    if let Some(f) = given {
        return f.coefficients();
    }
    let material = |name: &str| {
        if name == GROUND_NAME {
            (scene.ground.mu1, scene.ground.mu2)
        } else {
            scene
                .bodies
                .iter()
                .find(|b| b.name == name)
                .map_or((0.0, 0.0), |b| (b.mu1, b.mu2))
        }
    };
    let (a, b) = (material(a), material(b));
    (a.0.min(b.0), a.1.min(b.1))
}

fn join(values: &[f64]) -> String {
    values
        .iter()
        .map(f64::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

/// `text` as an XML attribute value.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_take_the_minimum_rule_or_the_scene_s_own_friction() {
        let mut scene = Scene::builtin("one_block").unwrap();
        assert_eq!(pair_friction(&scene, GROUND_NAME, "blockA"), (0.9, 0.9));
        assert_eq!(pair_friction(&scene, "actuator", "blockA"), (0.01, 0.01));
        scene.frictions.push(crate::scene::PairFriction {
            between: ["blockA".into(), GROUND_NAME.into()],
            mu1: 0.3,
            mu2: Some(0.2),
        });
        assert_eq!(pair_friction(&scene, GROUND_NAME, "blockA"), (0.3, 0.2));
        let xml = mjcf(&scene);
        assert!(xml
            .contains("geom1=\"ground_plane\" geom2=\"blockA\" condim=\"3\" friction=\"0.3 0.2 "));
        // Every pair once: three geoms, three pairs.
        assert_eq!(xml.matches("<pair ").count(), 3);
    }

    #[test]
    fn the_thesis_s_flat_block_has_an_inertia_no_solid_has() {
        let two = Scene::builtin("two_blocks").unwrap();
        assert_eq!(unphysical_inertia(&two).collect::<Vec<_>>(), ["blockB"]);
        let one = Scene::builtin("one_block").unwrap();
        assert_eq!(unphysical_inertia(&one).count(), 0);
    }

    #[test]
    fn box_sizes_are_half_extents_and_names_are_escaped() {
        let mut scene = Scene::builtin("one_block").unwrap();
        scene.bodies[1].name = "a<b&\"c".into();
        let xml = mjcf(&scene);
        assert!(
            xml.contains("type=\"box\" size=\"0.25 0.05 0.05\""),
            "{xml}"
        );
        assert!(xml.contains("name=\"a&lt;b&amp;&quot;c\""), "{xml}");
    }
}
