//! The scene's bodies by id and name (`docs/spec/README.md` §4,
//! `docs/spec/world.md` §3), the bodies a learner skips, and a body's name as
//! the wire carries it, parsed once: a scene body, or a
//! ghost pose of one (`docs/spec/protocol.md` §3). Ghosts are recognised by
//! the substring [`GHOST_MARKER`]; everything before its first occurrence
//! names the body the ghost stands for, everything after it says what kind
//! of ghost it is. [`BodyName`]'s `Display` gives back exactly the parsed
//! text, so a name survives a round trip through the type byte for byte.

use std::fmt;

/// Substring that marks a non-physical ghost pose (`docs/spec/protocol.md` §3): the
/// world never simulates such a body and learners skip it.
pub const GHOST_MARKER: &str = "Shadow";

/// Suffix after [`GHOST_MARKER`] of the ghost that marks a Move-to-Target
/// goal: `blockAShadowTarget` is the target pose of `blockA`, and the world
/// gives it blockA's id (docs/protocol.md §3, docs/viewer.md). A ghost
/// without suffix (`blockAShadow`) is a predicted pose.
pub const TARGET_GHOST_SUFFIX: &str = "Target";

/// Id of the actuator sphere (`docs/spec/README.md` §4, `docs/spec/world.md` §3).
pub const ACTUATOR_ID: u32 = 8;
/// Id of the blue block, `blockA` (0.5 × 0.1 m).
pub const BLUE_ID: u32 = 15;
/// Id of the red block, `blockB` (0.3 × 0.3 m), only in the two-object scene.
pub const RED_ID: u32 = 27;

/// Id of the cylinder, only in the new-object scene (`objects`).
pub const CYLINDER_ID: u32 = 33;

/// Model name of the actuator; `docs/spec/protocol.md` §4 identifies it by this exact name.
pub const ACTUATOR_NAME: &str = "actuator";
/// Model name of the blue block (id 15).
pub const BLUE_NAME: &str = "blockA";
/// Model name of the red block (id 27).
pub const RED_NAME: &str = "blockB";
/// Model name of the cylinder (id 33).
pub const CYLINDER_NAME: &str = "cylinder";

/// The ground's model name: the world reports contacts with it by this name,
/// a scene may not give it to a body, and learners skip it.
pub const GROUND_NAME: &str = "ground_plane";

/// The world's model name for an object id (`docs/spec/experiments.md` §2: SetPose
/// commands address bodies by name).
#[must_use]
pub fn object_name(id: u32) -> Option<&'static str> {
    match id {
        ACTUATOR_ID => Some(ACTUATOR_NAME),
        BLUE_ID => Some(BLUE_NAME),
        RED_ID => Some(RED_NAME),
        CYLINDER_ID => Some(CYLINDER_NAME),
        _ => None,
    }
}

/// Models the learner ignores (`docs/spec/protocol.md` §4): [`GROUND_NAME`],
/// anything whose name contains `wall` or [`GHOST_MARKER`].
#[must_use]
pub fn is_skipped(name: &str) -> bool {
    name == GROUND_NAME || name.contains("wall") || name.contains(GHOST_MARKER)
}

/// A name from a `ModelState` or a `SetPose`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum BodyName {
    /// A name without [`GHOST_MARKER`]: a simulated body, if the scene has
    /// one of that name.
    Body(String),
    /// A ghost pose, never simulated.
    Ghost(Ghost),
}

/// A ghost pose's name: `{of}Shadow{suffix}`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Ghost {
    /// The body the ghost stands for (`blockA` of `blockAShadow`). Any
    /// text parses (even empty); a world refuses a ghost whose body its
    /// scene lacks (the wire's `InvalidCommand::GhostOfUnknownBody`).
    pub of: String,
    pub kind: GhostKind,
}

/// What a ghost shows, from the text after [`GHOST_MARKER`].
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum GhostKind {
    /// No suffix: a learner's predicted pose (`blockAShadow`).
    Predicted,
    /// [`TARGET_GHOST_SUFFIX`]: a Move-to-Target goal (`blockAShadowTarget`).
    Target,
    /// Any other suffix, kept so that the name round-trips; the protocol
    /// gives it no meaning beyond being a ghost (the viewer draws it as a
    /// prediction).
    Other(String),
}

impl BodyName {
    /// Never fails: every string is a body name or a ghost's.
    #[must_use]
    pub fn parse(name: &str) -> Self {
        match name.split_once(GHOST_MARKER) {
            None => Self::Body(name.to_owned()),
            Some((of, suffix)) => Self::Ghost(Ghost {
                of: of.to_owned(),
                kind: match suffix {
                    "" => GhostKind::Predicted,
                    TARGET_GHOST_SUFFIX => GhostKind::Target,
                    other => GhostKind::Other(other.to_owned()),
                },
            }),
        }
    }

    /// The ghost, if this names one.
    #[must_use]
    pub fn ghost(&self) -> Option<&Ghost> {
        match self {
            Self::Body(_) => None,
            Self::Ghost(g) => Some(g),
        }
    }

    /// The scene body this name is drawn as or stands for: the body itself,
    /// or what a ghost is a ghost of.
    #[must_use]
    pub fn body(&self) -> &str {
        match self {
            Self::Body(name) => name,
            Self::Ghost(g) => &g.of,
        }
    }
}

impl Ghost {
    /// The predicted pose of `of`.
    #[must_use]
    pub fn predicted(of: impl Into<String>) -> Self {
        Self {
            of: of.into(),
            kind: GhostKind::Predicted,
        }
    }

    /// The Move-to-Target goal of `of`.
    #[must_use]
    pub fn target(of: impl Into<String>) -> Self {
        Self {
            of: of.into(),
            kind: GhostKind::Target,
        }
    }
}

impl From<&str> for BodyName {
    fn from(name: &str) -> Self {
        Self::parse(name)
    }
}

impl From<String> for BodyName {
    fn from(name: String) -> Self {
        Self::parse(&name)
    }
}

impl From<Ghost> for BodyName {
    fn from(ghost: Ghost) -> Self {
        Self::Ghost(ghost)
    }
}

impl fmt::Display for BodyName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Body(name) => f.write_str(name),
            Self::Ghost(g) => g.fmt(f),
        }
    }
}

impl fmt::Display for Ghost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let suffix = match &self.kind {
            GhostKind::Predicted => "",
            GhostKind::Target => TARGET_GHOST_SUFFIX,
            GhostKind::Other(s) => s,
        };
        write!(f, "{}{GHOST_MARKER}{suffix}", self.of)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn bodies_predictions_and_targets_are_told_apart() {
        assert_eq!(BodyName::parse("blockA"), BodyName::Body("blockA".into()));
        assert_eq!(
            BodyName::parse("actuatorShadow"),
            Ghost::predicted("actuator").into()
        );
        assert_eq!(
            BodyName::parse("blockAShadowTarget"),
            Ghost::target("blockA").into()
        );
        let old = BodyName::parse("blockBShadowOld");
        assert_eq!(old.body(), "blockB");
        assert_eq!(
            old.ghost().map(|g| &g.kind),
            Some(&GhostKind::Other("Old".into()))
        );
        // The marker anywhere makes a ghost, as the world has always had it.
        assert_eq!(
            BodyName::parse("Shadow").ghost(),
            Some(&Ghost::predicted(""))
        );
        assert_eq!(
            BodyName::parse("aShadowShadow").ghost().map(|g| &g.kind),
            Some(&GhostKind::Other("Shadow".into()))
        );
    }

    #[test]
    fn constructed_ghosts_print_the_wire_names() {
        assert_eq!(Ghost::predicted("blockA").to_string(), "blockAShadow");
        assert_eq!(Ghost::target("blockA").to_string(), "blockAShadowTarget");
    }

    #[test]
    fn the_learner_skips_the_ground_walls_and_ghosts_only() {
        for name in [
            "ground_plane",
            "wall",
            "northwall",
            "blockAShadow",
            "Shadow",
            "actuatorShadowTarget",
        ] {
            assert!(is_skipped(name), "{name}");
        }
        for name in [
            "actuator",
            "blockA",
            "blockB",
            "cylinder",
            "ground",
            "ground_plane2",
            "shadow",
        ] {
            assert!(!is_skipped(name), "{name}");
        }
    }

    #[test]
    fn every_id_names_its_body() {
        for (id, name) in [
            (8, "actuator"),
            (15, "blockA"),
            (27, "blockB"),
            (33, "cylinder"),
        ] {
            assert_eq!(object_name(id), Some(name));
        }
        assert_eq!(object_name(0), None);
    }

    proptest! {
        #[test]
        fn every_name_round_trips(name in "(block|Shadow|Target|x|)*") {
            prop_assert_eq!(BodyName::parse(&name).to_string(), name);
        }

        #[test]
        fn a_ghost_is_what_contains_the_marker(name in ".*") {
            prop_assert_eq!(BodyName::parse(&name).ghost().is_some(), name.contains(GHOST_MARKER));
        }
    }
}
