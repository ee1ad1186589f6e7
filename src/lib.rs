//! pushlearn: wire types, client, learner daemon, experiments.
//!
//! * [`wire`]: the protobuf schema (`proto/pushlearn.proto`), framing,
//!   connections and command validation shared by the world daemon and its
//!   clients;
//! * [`client`]: an async client for the world daemon;
//! * [`frame`]: world states as the learner sees them;
//! * [`experiment`]: the thesis's experiments over the sockets;
//! * [`learn`]: the learner daemon;
//! * [`load`]: a load test of a world daemon (`pushlearn ctl load`);
//! * [`models`]: the learners by name;
//! * [`report`]: JSON documents and terminal tables beside the thesis's numbers;
//! * [`view`]: the browser viewer (`pushlearn view`).

pub mod client;
pub mod experiment;
pub mod frame;
pub mod latency;
pub mod learn;
pub mod load;
pub mod models;
pub mod report;
pub mod view;
pub mod wire;
