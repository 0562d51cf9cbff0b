//! The command line's room: the `run` pipeline ([`app`]) behind the
//! `ldcbf-sim` binary, whose argument parsing is `src/main.rs`. The top room:
//! it may use every other one.

pub mod app;
