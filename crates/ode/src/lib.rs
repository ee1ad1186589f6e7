//! Safe wrapper over ode-sys (filled in by the foundation work).
