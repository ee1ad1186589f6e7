//! End-to-end tests over localhost sockets, compiled as one test binary.
//!
//! The world on the other end is the real daemon, `pushlearn-sim`, run as a
//! child process ([`daemon::Daemon`]); it must have been built
//! (`cargo build -p sim-plugin`; `cargo test --workspace` does it).

mod browser;
mod daemon;
mod process;

mod client;
mod ctl;
mod docs;
mod experiment;
mod exposure;
mod first_hour;
mod identity;
mod learner;
mod python;
mod record;
mod reliability;
mod reproduce;
mod viewer;
