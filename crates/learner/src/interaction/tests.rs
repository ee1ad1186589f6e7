//! Tests of the interaction model.
