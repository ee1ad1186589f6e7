//! The thesis's numbers, as data, each table with its source in
//! `docs/spec/reference-results.md` ([text]: printed in the thesis;
//! [figure]: read out of its vector figures to about ±0.0005). The report
//! prints them beside ours; nothing else uses them.

// Reference tables are data: one struct literal per line keeps them
// comparable with the source tables line by line.
#![allow(clippy::unreadable_literal)]

/// Mean ± standard deviation as the thesis reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ms(pub f64, pub f64);

/// One N_train of a learning curve (§3.2, §3.4): all 21 positions and the
/// 15 interacting ones; the actuator over the interacting positions is the
/// original script's (mean + std) / 2 value (`docs/spec/experiments.md` §7.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveRef {
    pub train_runs: usize,
    pub pos: Ms,
    pub pos_interacting: Ms,
    pub ori: Ms,
    pub ori_interacting: Ms,
    pub actuator: Ms,
    pub actuator_interacting_quirk: Ms,
}

/// Interaction model node counts of one N_train (§4.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InteractionNodesRef {
    pub train_runs: usize,
    pub ac_updates: Ms,
    pub ac_nodes: Ms,
    pub ac_count: Ms,
    pub acs_updates: f64,
    pub acs_nodes: Ms,
}

/// Gate model node counts of one N_train (§4.2); the actuator model always
/// has 2 nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GateNodesRef {
    pub train_runs: usize,
    pub object_updates: Ms,
    pub object_nodes: Ms,
    pub gate_updates: f64,
    pub gate_nodes: Ms,
}

/// One test position of a per-position table (§5.2, §5.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionRef {
    pub x0: f64,
    pub pos: Ms,
    pub ori: Ms,
}

/// One test position of the two-object tables (§6.1, §6.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoObjectRef {
    pub x0: f64,
    pub red_pos: Ms,
    pub red_ori: Ms,
    pub blue_pos: Ms,
    pub blue_ori: Ms,
}

/// One target of a Move-to-Target table (§8): reached count of 5, mean
/// remaining errors of the failed runs, mean steps (bracket: successful runs
/// only, shown when some failed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MttRef {
    pub reached: usize,
    pub pos: Option<f64>,
    pub ori: Option<f64>,
    pub steps: f64,
    pub steps_reached: Option<f64>,
}

/// The learning curve of `model` for `train_runs`, if the thesis has it.
#[must_use]
pub fn curve(model: learner::registry::ModelKind, train_runs: usize) -> Option<&'static CurveRef> {
    let table: &[CurveRef] = match model.family() {
        learner::registry::ThesisModel::Gate => &GATE_CURVE,
        learner::registry::ThesisModel::Interaction => &INTERACTION_CURVE,
    };
    table.iter().find(|r| r.train_runs == train_runs)
}

/// The per-position table of the three selected training runs for `model`.
#[must_use]
pub fn fixed_three(model: learner::registry::ModelKind) -> &'static [PositionRef; 21] {
    match model.family() {
        learner::registry::ThesisModel::Gate => &GATE_FIXED_THREE,
        learner::registry::ThesisModel::Interaction => &INTERACTION_FIXED_THREE,
    }
}

/// The two-object table for `train_runs` (6 or 7).
#[must_use]
pub fn two_objects(train_runs: usize) -> Option<&'static [TwoObjectRef; 21]> {
    match train_runs {
        6 => Some(&TWO_OBJECTS_SIX),
        7 => Some(&TWO_OBJECTS_SEVEN),
        _ => None,
    }
}

/// The Move-to-Target table of `model`, targets 1–4 in order.
#[must_use]
pub fn move_to_target(model: learner::registry::ModelKind) -> &'static [MttRef; 4] {
    match model.family() {
        learner::registry::ThesisModel::Gate => &GATE_MTT,
        learner::registry::ThesisModel::Interaction => &INTERACTION_MTT,
    }
}

/// Interaction model learning curve, random training data: `docs/spec/reference-results.md` §3.2 [figure].
pub const INTERACTION_CURVE: [CurveRef; 7] = [
    CurveRef {
        train_runs: 1,
        pos: Ms(0.2369, 0.1467),
        pos_interacting: Ms(0.2158, 0.1365),
        ori: Ms(0.7996, 0.5044),
        ori_interacting: Ms(0.8374, 0.5874),
        actuator: Ms(0.0318, 0.0205),
        actuator_interacting_quirk: Ms(0.0255, 0.0203),
    },
    CurveRef {
        train_runs: 2,
        pos: Ms(0.2627, 0.1656),
        pos_interacting: Ms(0.2103, 0.1565),
        ori: Ms(0.5527, 0.4142),
        ori_interacting: Ms(0.5515, 0.4495),
        actuator: Ms(0.0528, 0.0439),
        actuator_interacting_quirk: Ms(0.0446, 0.0394),
    },
    CurveRef {
        train_runs: 3,
        pos: Ms(0.2056, 0.1569),
        pos_interacting: Ms(0.1642, 0.1478),
        ori: Ms(0.4131, 0.2777),
        ori_interacting: Ms(0.3512, 0.2735),
        actuator: Ms(0.0494, 0.0392),
        actuator_interacting_quirk: Ms(0.0421, 0.0355),
    },
    CurveRef {
        train_runs: 5,
        pos: Ms(0.168, 0.1291),
        pos_interacting: Ms(0.1253, 0.1227),
        ori: Ms(0.3919, 0.243),
        ori_interacting: Ms(0.2637, 0.2594),
        actuator: Ms(0.0466, 0.0333),
        actuator_interacting_quirk: Ms(0.0413, 0.0357),
    },
    CurveRef {
        train_runs: 10,
        pos: Ms(0.1168, 0.0836),
        pos_interacting: Ms(0.0867, 0.0863),
        ori: Ms(0.3266, 0.164),
        ori_interacting: Ms(0.1802, 0.1717),
        actuator: Ms(0.0408, 0.0319),
        actuator_interacting_quirk: Ms(0.0356, 0.0316),
    },
    CurveRef {
        train_runs: 20,
        pos: Ms(0.1039, 0.0737),
        pos_interacting: Ms(0.0717, 0.0748),
        ori: Ms(0.2811, 0.1153),
        ori_interacting: Ms(0.127, 0.1144),
        actuator: Ms(0.0345, 0.0214),
        actuator_interacting_quirk: Ms(0.0274, 0.0212),
    },
    CurveRef {
        train_runs: 30,
        pos: Ms(0.0858, 0.0469),
        pos_interacting: Ms(0.0556, 0.0501),
        ori: Ms(0.2502, 0.0875),
        ori_interacting: Ms(0.0952, 0.0844),
        actuator: Ms(0.0331, 0.0189),
        actuator_interacting_quirk: Ms(0.0276, 0.0206),
    },
];
/// Gate model learning curve, random training data: `docs/spec/reference-results.md` §3.4 [figure].
pub const GATE_CURVE: [CurveRef; 7] = [
    CurveRef {
        train_runs: 1,
        pos: Ms(0.2245, 0.1502),
        pos_interacting: Ms(0.223, 0.1265),
        ori: Ms(0.8934, 0.6805),
        ori_interacting: Ms(1.0248, 0.7235),
        actuator: Ms(0.0022, 0.0004),
        actuator_interacting_quirk: Ms(0.0014, 0.0004),
    },
    CurveRef {
        train_runs: 2,
        pos: Ms(0.1554, 0.132),
        pos_interacting: Ms(0.1676, 0.1133),
        ori: Ms(0.3682, 0.3327),
        ori_interacting: Ms(0.4466, 0.3581),
        actuator: Ms(0.0022, 0.0004),
        actuator_interacting_quirk: Ms(0.0013, 0.0004),
    },
    CurveRef {
        train_runs: 3,
        pos: Ms(0.1405, 0.1292),
        pos_interacting: Ms(0.1557, 0.1154),
        ori: Ms(0.3543, 0.3863),
        ori_interacting: Ms(0.4472, 0.425),
        actuator: Ms(0.0022, 0.0004),
        actuator_interacting_quirk: Ms(0.0014, 0.0004),
    },
    CurveRef {
        train_runs: 5,
        pos: Ms(0.0864, 0.0897),
        pos_interacting: Ms(0.1081, 0.0871),
        ori: Ms(0.2267, 0.195),
        ori_interacting: Ms(0.2999, 0.2221),
        actuator: Ms(0.0022, 0.0004),
        actuator_interacting_quirk: Ms(0.0014, 0.0004),
    },
    CurveRef {
        train_runs: 10,
        pos: Ms(0.0487, 0.0432),
        pos_interacting: Ms(0.0647, 0.0499),
        ori: Ms(0.1521, 0.1195),
        ori_interacting: Ms(0.2026, 0.1393),
        actuator: Ms(0.0022, 0.0004),
        actuator_interacting_quirk: Ms(0.0013, 0.0004),
    },
    CurveRef {
        train_runs: 20,
        pos: Ms(0.0371, 0.0334),
        pos_interacting: Ms(0.0507, 0.0435),
        ori: Ms(0.1182, 0.0908),
        ori_interacting: Ms(0.1635, 0.1225),
        actuator: Ms(0.0022, 0.0003),
        actuator_interacting_quirk: Ms(0.0013, 0.0004),
    },
    CurveRef {
        train_runs: 30,
        pos: Ms(0.036, 0.0274),
        pos_interacting: Ms(0.0503, 0.038),
        ori: Ms(0.1093, 0.0806),
        ori_interacting: Ms(0.1526, 0.111),
        actuator: Ms(0.0022, 0.0005),
        actuator_interacting_quirk: Ms(0.0014, 0.0005),
    },
];
/// Interaction model node counts after training: `docs/spec/reference-results.md` §4.1 [text].
/// "AC Updates / AC Nodes" and "# ACs" are the original script's quirky values (§7.5).
pub const INTERACTION_NODES: [InteractionNodesRef; 7] = [
    InteractionNodesRef {
        train_runs: 1,
        ac_updates: Ms(59.74, 7.93),
        ac_nodes: Ms(17.58, 13.14),
        ac_count: Ms(6.9, 0.45),
        acs_updates: 149.0,
        acs_nodes: Ms(39.65, 11.49),
    },
    InteractionNodesRef {
        train_runs: 2,
        ac_updates: Ms(98.37, 24.63),
        ac_nodes: Ms(28.32, 21.68),
        ac_count: Ms(9.58, 1.93),
        acs_updates: 298.0,
        acs_nodes: Ms(85.45, 17.22),
    },
    InteractionNodesRef {
        train_runs: 3,
        ac_updates: Ms(132.0, 27.26),
        ac_nodes: Ms(28.9, 19.1),
        ac_count: Ms(10.37, 2.25),
        acs_updates: 447.0,
        acs_nodes: Ms(124.35, 22.57),
    },
    InteractionNodesRef {
        train_runs: 5,
        ac_updates: Ms(224.84, 29.69),
        ac_nodes: Ms(51.05, 25.84),
        ac_count: Ms(11.42, 2.23),
        acs_updates: 745.0,
        acs_nodes: Ms(196.75, 29.23),
    },
    InteractionNodesRef {
        train_runs: 10,
        ac_updates: Ms(453.37, 62.96),
        ac_nodes: Ms(106.21, 61.37),
        ac_count: Ms(12.63, 2.98),
        acs_updates: 1490.0,
        acs_nodes: Ms(372.55, 21.93),
    },
    InteractionNodesRef {
        train_runs: 20,
        ac_updates: Ms(876.11, 78.19),
        ac_nodes: Ms(182.53, 94.63),
        ac_count: Ms(15.58, 1.09),
        acs_updates: 2980.0,
        acs_nodes: Ms(740.15, 47.08),
    },
    InteractionNodesRef {
        train_runs: 30,
        ac_updates: Ms(1209.89, 146.47),
        ac_nodes: Ms(239.42, 130.38),
        ac_count: Ms(16.32, 1.03),
        acs_updates: 4470.0,
        acs_nodes: Ms(1086.95, 76.74),
    },
];
/// Gate model node counts after training: `docs/spec/reference-results.md` §4.2 [text].
pub const GATE_NODES: [GateNodesRef; 7] = [
    GateNodesRef {
        train_runs: 1,
        object_updates: Ms(93.5, 16.87),
        object_nodes: Ms(26.55, 11.01),
        gate_updates: 149.0,
        gate_nodes: Ms(3.7, 0.46),
    },
    GateNodesRef {
        train_runs: 2,
        object_updates: Ms(194.35, 27.43),
        object_nodes: Ms(39.4, 15.87),
        gate_updates: 298.0,
        gate_nodes: Ms(5.55, 1.07),
    },
    GateNodesRef {
        train_runs: 3,
        object_updates: Ms(287.25, 33.85),
        object_nodes: Ms(67.4, 20.44),
        gate_updates: 447.0,
        gate_nodes: Ms(6.4, 1.07),
    },
    GateNodesRef {
        train_runs: 5,
        object_updates: Ms(479.6, 42.91),
        object_nodes: Ms(111.95, 20.46),
        gate_updates: 745.0,
        gate_nodes: Ms(6.8, 1.07),
    },
    GateNodesRef {
        train_runs: 10,
        object_updates: Ms(963.7, 37.04),
        object_nodes: Ms(219.65, 38.24),
        gate_updates: 1490.0,
        gate_nodes: Ms(7.75, 0.89),
    },
    GateNodesRef {
        train_runs: 20,
        object_updates: Ms(1894.25, 46.3),
        object_nodes: Ms(438.2, 45.17),
        gate_updates: 2980.0,
        gate_nodes: Ms(10.4, 6.88),
    },
    GateNodesRef {
        train_runs: 30,
        object_updates: Ms(2883.8, 111.4),
        object_nodes: Ms(603.05, 36.16),
        gate_updates: 4470.0,
        gate_nodes: Ms(10.2, 4.23),
    },
];
/// Interaction model, three selected training runs, per test position:
/// `docs/spec/reference-results.md` §5.2 [figure].
pub const INTERACTION_FIXED_THREE: [PositionRef; 21] = [
    PositionRef {
        x0: -0.35,
        pos: Ms(0.1783, 0.0119),
        ori: Ms(0.7664, 0.0159),
    },
    PositionRef {
        x0: -0.315,
        pos: Ms(0.1793, 0.012),
        ori: Ms(0.7724, 0.0154),
    },
    PositionRef {
        x0: -0.28,
        pos: Ms(0.1815, 0.0123),
        ori: Ms(0.7859, 0.0153),
    },
    PositionRef {
        x0: -0.245,
        pos: Ms(0.0478, 0.0136),
        ori: Ms(0.2173, 0.0138),
    },
    PositionRef {
        x0: -0.21,
        pos: Ms(0.0166, 0.0085),
        ori: Ms(0.0806, 0.0135),
    },
    PositionRef {
        x0: -0.175,
        pos: Ms(0.0239, 0.0129),
        ori: Ms(0.0127, 0.0102),
    },
    PositionRef {
        x0: -0.14,
        pos: Ms(0.0439, 0.0159),
        ori: Ms(0.1064, 0.0106),
    },
    PositionRef {
        x0: -0.105,
        pos: Ms(0.0659, 0.0163),
        ori: Ms(0.2024, 0.0099),
    },
    PositionRef {
        x0: -0.07,
        pos: Ms(0.0536, 0.0205),
        ori: Ms(0.4484, 0.0068),
    },
    PositionRef {
        x0: -0.035,
        pos: Ms(0.0323, 0.0159),
        ori: Ms(0.1683, 0.0064),
    },
    PositionRef {
        x0: 0.0,
        pos: Ms(0.0292, 0.0156),
        ori: Ms(0.0043, 0.0005),
    },
    PositionRef {
        x0: 0.035,
        pos: Ms(0.0321, 0.016),
        ori: Ms(0.1623, 0.0033),
    },
    PositionRef {
        x0: 0.07,
        pos: Ms(0.0542, 0.0213),
        ori: Ms(0.4553, 0.0068),
    },
    PositionRef {
        x0: 0.105,
        pos: Ms(0.0728, 0.0163),
        ori: Ms(0.2328, 0.0157),
    },
    PositionRef {
        x0: 0.14,
        pos: Ms(0.0525, 0.0161),
        ori: Ms(0.1413, 0.0153),
    },
    PositionRef {
        x0: 0.175,
        pos: Ms(0.0303, 0.0164),
        ori: Ms(0.0485, 0.0152),
    },
    PositionRef {
        x0: 0.21,
        pos: Ms(0.0167, 0.0071),
        ori: Ms(0.0373, 0.014),
    },
    PositionRef {
        x0: 0.245,
        pos: Ms(0.0394, 0.0162),
        ori: Ms(0.1749, 0.0152),
    },
    PositionRef {
        x0: 0.28,
        pos: Ms(0.1739, 0.0166),
        ori: Ms(0.7474, 0.0166),
    },
    PositionRef {
        x0: 0.315,
        pos: Ms(0.1719, 0.0158),
        ori: Ms(0.7359, 0.015),
    },
    PositionRef {
        x0: 0.35,
        pos: Ms(0.1701, 0.0159),
        ori: Ms(0.7317, 0.0158),
    },
];
/// Gate model, three selected training runs, per test position:
/// `docs/spec/reference-results.md` §5.3 [figure].
pub const GATE_FIXED_THREE: [PositionRef; 21] = [
    PositionRef {
        x0: -0.35,
        pos: Ms(0.0, 0.0),
        ori: Ms(0.0, 0.0),
    },
    PositionRef {
        x0: -0.315,
        pos: Ms(0.0, 0.0),
        ori: Ms(0.0, 0.0),
    },
    PositionRef {
        x0: -0.28,
        pos: Ms(0.0, 0.0),
        ori: Ms(0.0, 0.0),
    },
    PositionRef {
        x0: -0.245,
        pos: Ms(0.14, 0.0),
        ori: Ms(0.5778, 0.0006),
    },
    PositionRef {
        x0: -0.21,
        pos: Ms(0.0901, 0.0375),
        ori: Ms(0.3131, 0.1379),
    },
    PositionRef {
        x0: -0.175,
        pos: Ms(0.0379, 0.0214),
        ori: Ms(0.0844, 0.0661),
    },
    PositionRef {
        x0: -0.14,
        pos: Ms(0.0358, 0.0098),
        ori: Ms(0.0603, 0.0448),
    },
    PositionRef {
        x0: -0.105,
        pos: Ms(0.0398, 0.0212),
        ori: Ms(0.1656, 0.0322),
    },
    PositionRef {
        x0: -0.07,
        pos: Ms(0.0345, 0.0052),
        ori: Ms(0.4444, 0.0431),
    },
    PositionRef {
        x0: -0.035,
        pos: Ms(0.0085, 0.0045),
        ori: Ms(0.1588, 0.0419),
    },
    PositionRef {
        x0: 0.0,
        pos: Ms(0.0039, 0.0047),
        ori: Ms(0.037, 0.0199),
    },
    PositionRef {
        x0: 0.035,
        pos: Ms(0.0086, 0.0044),
        ori: Ms(0.1731, 0.0404),
    },
    PositionRef {
        x0: 0.07,
        pos: Ms(0.0349, 0.0047),
        ori: Ms(0.4609, 0.0403),
    },
    PositionRef {
        x0: 0.105,
        pos: Ms(0.0682, 0.029),
        ori: Ms(0.1653, 0.0529),
    },
    PositionRef {
        x0: 0.14,
        pos: Ms(0.0524, 0.0177),
        ori: Ms(0.1435, 0.048),
    },
    PositionRef {
        x0: 0.175,
        pos: Ms(0.0424, 0.017),
        ori: Ms(0.1347, 0.0614),
    },
    PositionRef {
        x0: 0.21,
        pos: Ms(0.055, 0.0108),
        ori: Ms(0.2765, 0.022),
    },
    PositionRef {
        x0: 0.245,
        pos: Ms(0.14, 0.0),
        ori: Ms(0.5778, 0.0006),
    },
    PositionRef {
        x0: 0.28,
        pos: Ms(0.0, 0.0),
        ori: Ms(0.0, 0.0),
    },
    PositionRef {
        x0: 0.315,
        pos: Ms(0.0, 0.0),
        ori: Ms(0.0, 0.0),
    },
    PositionRef {
        x0: 0.35,
        pos: Ms(0.0, 0.0),
        ori: Ms(0.0, 0.0),
    },
];
/// Gate model, two objects, six training runs: `docs/spec/reference-results.md` §6.1 [figure].
pub const TWO_OBJECTS_SIX: [TwoObjectRef; 21] = [
    TwoObjectRef {
        x0: -0.8,
        red_pos: Ms(0.2173, 0.0157),
        red_ori: Ms(1.1969, 0.0402),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.74,
        red_pos: Ms(0.2072, 0.0355),
        red_ori: Ms(0.7285, 0.1358),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.68,
        red_pos: Ms(0.0286, 0.0142),
        red_ori: Ms(0.0831, 0.0635),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.62,
        red_pos: Ms(0.0098, 0.0006),
        red_ori: Ms(0.016, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.56,
        red_pos: Ms(0.0106, 0.0007),
        red_ori: Ms(0.0324, 0.0005),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.5,
        red_pos: Ms(0.0451, 0.0217),
        red_ori: Ms(0.1657, 0.0798),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.44,
        red_pos: Ms(0.2751, 0.0829),
        red_ori: Ms(0.5169, 0.1552),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.38,
        red_pos: Ms(0.1688, 0.0363),
        red_ori: Ms(0.9888, 0.1195),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.32,
        red_pos: Ms(0.1267, 0.0324),
        red_ori: Ms(0.7831, 0.0634),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.26,
        red_pos: Ms(0.0806, 0.0207),
        red_ori: Ms(0.4983, 0.0247),
        blue_pos: Ms(0.1115, 0.0),
        blue_ori: Ms(0.4597, 0.0013),
    },
    TwoObjectRef {
        x0: -0.2,
        red_pos: Ms(0.024, 0.0055),
        red_ori: Ms(0.1511, 0.0026),
        blue_pos: Ms(0.0551, 0.0188),
        blue_ori: Ms(0.1502, 0.0609),
    },
    TwoObjectRef {
        x0: -0.14,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0489, 0.0242),
        blue_ori: Ms(0.114, 0.0493),
    },
    TwoObjectRef {
        x0: -0.08,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.2433, 0.064),
        blue_ori: Ms(1.0222, 0.0823),
    },
    TwoObjectRef {
        x0: -0.02,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0067, 0.0043),
        blue_ori: Ms(0.1032, 0.0234),
    },
    TwoObjectRef {
        x0: 0.04,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.011, 0.0046),
        blue_ori: Ms(0.1832, 0.024),
    },
    TwoObjectRef {
        x0: 0.1,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.1134, 0.0334),
        blue_ori: Ms(0.2712, 0.0642),
    },
    TwoObjectRef {
        x0: 0.16,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0703, 0.0203),
        blue_ori: Ms(0.2041, 0.08),
    },
    TwoObjectRef {
        x0: 0.22,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0678, 0.0324),
        blue_ori: Ms(0.3307, 0.0921),
    },
    TwoObjectRef {
        x0: 0.28,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: 0.34,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: 0.4,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
];
/// Gate model, two objects, seven training runs: `docs/spec/reference-results.md` §6.2 [figure].
pub const TWO_OBJECTS_SEVEN: [TwoObjectRef; 21] = [
    TwoObjectRef {
        x0: -0.8,
        red_pos: Ms(0.2333, 0.0135),
        red_ori: Ms(1.2476, 0.0351),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.74,
        red_pos: Ms(0.1963, 0.0464),
        red_ori: Ms(0.6845, 0.1711),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.68,
        red_pos: Ms(0.0396, 0.0155),
        red_ori: Ms(0.1298, 0.0476),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.62,
        red_pos: Ms(0.0095, 0.0008),
        red_ori: Ms(0.016, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.56,
        red_pos: Ms(0.0103, 0.0008),
        red_ori: Ms(0.0322, 0.0014),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.5,
        red_pos: Ms(0.0383, 0.0221),
        red_ori: Ms(0.1366, 0.0756),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.44,
        red_pos: Ms(0.2032, 0.1041),
        red_ori: Ms(0.4926, 0.1206),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.38,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.32,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: -0.26,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.1117, 0.0003),
        blue_ori: Ms(0.4603, 0.0014),
    },
    TwoObjectRef {
        x0: -0.2,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0555, 0.0102),
        blue_ori: Ms(0.1579, 0.0426),
    },
    TwoObjectRef {
        x0: -0.14,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0615, 0.0131),
        blue_ori: Ms(0.1389, 0.0375),
    },
    TwoObjectRef {
        x0: -0.08,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.2564, 0.0606),
        blue_ori: Ms(1.0479, 0.0918),
    },
    TwoObjectRef {
        x0: -0.02,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0057, 0.0011),
        blue_ori: Ms(0.1082, 0.0273),
    },
    TwoObjectRef {
        x0: 0.04,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0106, 0.0016),
        blue_ori: Ms(0.1806, 0.026),
    },
    TwoObjectRef {
        x0: 0.1,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0976, 0.0409),
        blue_ori: Ms(0.2359, 0.0553),
    },
    TwoObjectRef {
        x0: 0.16,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0603, 0.0185),
        blue_ori: Ms(0.1777, 0.068),
    },
    TwoObjectRef {
        x0: 0.22,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0589, 0.0306),
        blue_ori: Ms(0.3144, 0.0796),
    },
    TwoObjectRef {
        x0: 0.28,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: 0.34,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
    TwoObjectRef {
        x0: 0.4,
        red_pos: Ms(0.0, 0.0),
        red_ori: Ms(0.0, 0.0),
        blue_pos: Ms(0.0, 0.0),
        blue_ori: Ms(0.0, 0.0),
    },
];
/// Interaction model, Move to Target, targets 1–4: `docs/spec/reference-results.md` §8.1 [text].
pub const INTERACTION_MTT: [MttRef; 4] = [
    MttRef {
        reached: 3,
        pos: Some(0.55),
        ori: Some(0.002),
        steps: 2689.2,
        steps_reached: Some(2482.0),
    },
    MttRef {
        reached: 4,
        pos: Some(0.01),
        ori: Some(0.023),
        steps: 2430.4,
        steps_reached: Some(2288.0),
    },
    MttRef {
        reached: 5,
        pos: None,
        ori: None,
        steps: 1377.6,
        steps_reached: None,
    },
    MttRef {
        reached: 2,
        pos: Some(0.55),
        ori: Some(2.04),
        steps: 2492.2,
        steps_reached: Some(1730.5),
    },
];
/// Gate model, Move to Target, targets 1–4: `docs/spec/reference-results.md` §8.2 [text].
pub const GATE_MTT: [MttRef; 4] = [
    MttRef {
        reached: 4,
        pos: Some(0.01),
        ori: Some(0.002),
        steps: 2271.0,
        steps_reached: Some(2088.8),
    },
    MttRef {
        reached: 5,
        pos: None,
        ori: None,
        steps: 1695.0,
        steps_reached: None,
    },
    MttRef {
        reached: 5,
        pos: None,
        ori: None,
        steps: 1147.4,
        steps_reached: None,
    },
    MttRef {
        reached: 5,
        pos: None,
        ori: None,
        steps: 1597.4,
        steps_reached: None,
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_complete_and_ordered() {
        let runs: Vec<usize> = GATE_CURVE.iter().map(|r| r.train_runs).collect();
        assert_eq!(runs, [1, 2, 3, 5, 10, 20, 30]);
        assert_eq!(
            INTERACTION_CURVE.map(|r| r.train_runs),
            GATE_CURVE.map(|r| r.train_runs)
        );
        assert_eq!(
            GATE_NODES.map(|r| r.train_runs),
            GATE_CURVE.map(|r| r.train_runs)
        );
        assert_eq!(
            INTERACTION_NODES.map(|r| r.train_runs),
            GATE_CURVE.map(|r| r.train_runs)
        );
        // 149 updates per training run (`docs/spec/experiments.md` §8).
        for r in GATE_NODES {
            assert_eq!(r.gate_updates, 149.0 * r.train_runs as f64);
        }
        for r in INTERACTION_NODES {
            assert_eq!(r.acs_updates, 149.0 * r.train_runs as f64);
        }
        // Test positions −0.35 + 0.035 i and −0.8 + 0.06 i.
        for (i, r) in GATE_FIXED_THREE.iter().enumerate() {
            assert!((r.x0 - (-0.35 + 0.035 * i as f64)).abs() < 1e-9);
            assert_eq!(r.x0, INTERACTION_FIXED_THREE[i].x0);
        }
        for (i, r) in TWO_OBJECTS_SIX.iter().enumerate() {
            assert!((r.x0 - (-0.8 + 0.06 * i as f64)).abs() < 1e-9);
            assert_eq!(r.x0, TWO_OBJECTS_SEVEN[i].x0);
        }
    }

    #[test]
    fn spot_checks_against_the_source() {
        assert_eq!(GATE_CURVE[4].pos, Ms(0.0487, 0.0432));
        assert_eq!(INTERACTION_CURVE[6].ori, Ms(0.2502, 0.0875));
        assert_eq!(GATE_NODES[6].object_nodes, Ms(603.05, 36.16));
        assert_eq!(INTERACTION_FIXED_THREE[8].ori, Ms(0.4484, 0.0068));
        assert_eq!(GATE_FIXED_THREE[3].pos, Ms(0.14, 0.0));
        assert_eq!(TWO_OBJECTS_SEVEN[12].blue_ori, Ms(1.0479, 0.0918));
        assert_eq!(INTERACTION_MTT[3].steps_reached, Some(1730.5));
        assert_eq!(GATE_MTT[1].pos, None);
    }
}
