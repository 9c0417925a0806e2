//! End-to-end tests of rfta across crates, against the shared data (`../shared/data`).
//!
//! The tests live in `e2e/`, compiled as one binary; this library is empty.
