//! pushlearn: wire types, client, learner daemon, experiments.
