//! The thesis world and the simulator daemon.
