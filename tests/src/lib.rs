//! sinew-tests holds sinew's end-to-end tests: whole pipelines (import → compile → bake → verify,
//! compression and LODs) on the committed fixtures and the shared corpus, and the command-line contract
//! (exit codes, one-line errors, atomic outputs, JSON reports, determinism across runs and thread
//! counts). The tests are in `tests/tests/`; the library itself is empty.
//!
//! Where tests live in sinew: unit tests beside their code; a crate's own integration tests (one crate's
//! behaviour, on its inputs) in that crate's `tests/`; anything that runs several crates as a whole, or
//! the `sinew` binary, here. The binary under test is `sinew-e2e` (`src/bin`), the same code as `sinew`.
