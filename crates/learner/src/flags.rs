//! Configuration bits of the original (`docs/spec/experiments.md` §1): the gate model
//! reads 1, 2, 16, 32 and 64 (`GateParams::from_config_number`), the
//! interaction model 2 (`InteractionParams::from_config_number`), the
//! experiment driver 2, 4 and 8.

/// Velocity features (the thesis draft's dynamics features, §4.3.1).
pub const USE_DYNS: u32 = 1;
/// 10 Hz thresholds.
pub const LOWFREQ: u32 = 2;
/// Driver only (training start range).
pub const ALLOWMISSPOSITIONS: u32 = 4;
/// Driver only (fixed first training runs).
pub const FIXFIRSTTHREETRAININGRUNS: u32 = 8;
/// Hard-coded actuator forward model.
pub const HARDCODEDACT: u32 = 16;
/// Hard-coded gate.
pub const HARDCODEDGATE: u32 = 32;
/// Prediction boost 1.5.
pub const USINGPREDICTIONBOOST: u32 = 64;
/// Every bit the original defined.
pub const ALL: u32 = 127;
/// The bits that concern only the driver (`docs/spec/experiments.md` §1).
pub const DRIVER: u32 = ALLOWMISSPOSITIONS | FIXFIRSTTHREETRAININGRUNS;
