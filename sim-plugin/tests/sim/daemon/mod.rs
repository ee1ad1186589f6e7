//! The `pushlearn-sim` daemon over real localhost sockets: in-process
//! servers bound to 127.0.0.1:0, and the binary itself.

mod support;

mod bad_input;
mod binary;
mod clients;
mod commands;
mod lockstep;
#[cfg(feature = "mujoco")]
mod mujoco;
