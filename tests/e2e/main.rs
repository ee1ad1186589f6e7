//! End-to-end tests over localhost sockets, compiled as one test binary.
//!
//! Until `pushlearn-sim` exists, the world on the other end is
//! [`fake_world::FakeWorld`], which speaks the real protocol.

mod fake_world;
mod process;

mod client;
mod ctl;
mod docs;
mod python;
