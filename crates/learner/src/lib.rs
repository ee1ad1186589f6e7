//! pushlearn models (filled in by the learner work).

pub mod aim;
pub mod aitm;
