//! Workspace root package: hosts the cross-crate integration tests in `tests/` and the benchmarks in `benches/`.
