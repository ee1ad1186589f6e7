//! The world's tests, compiled as one test binary since linking each file
//! separately costs minutes on two cores:
//!
//! * [`world`], [`calibration`]: the in-process world and the thesis's
//!   calibration checks (`docs/spec/world.md` §10);
//! * [`scene_features`]: what scene files say about objects beyond the
//!   thesis's (pair friction, centre of mass, computed inertia, free ids);
//! * [`generated_objects`]: generated objects loaded and pushed;
//! * [`daemon`]: the `pushlearn-sim` daemon over real localhost sockets;
//! * [`gate_push_task`], [`interaction_push_task`]: the learners trained and
//!   tested on pushes of this world, in-process (trace-driven).

#[path = "../support/push_frames.rs"]
mod push_frames;

mod calibration;
mod daemon;
mod gate_push_task;
mod generated_objects;
mod interaction_push_task;
mod scene_features;
mod world;
