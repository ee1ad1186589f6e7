//! Raw FFI bindings to ODE (filled in by the foundation work).
