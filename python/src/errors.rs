//! The exceptions the extension raises: [`SinewError`] and its two kinds, [`InputError`] (a bad or
//! missing file) and [`UsageError`] (bad arguments), as the command line's exit code 2 splits them.

use pyo3::create_exception;
use pyo3::exceptions::PyException;

create_exception!(
    _sinew,
    SinewError,
    PyException,
    "An error from sinew; `args[0]` is its one-line message (FILE: section at offset: problem)."
);
create_exception!(
    _sinew,
    InputError,
    SinewError,
    "Bad input: a missing, unreadable or corrupt file (the CLI's exit code 2)."
);
create_exception!(
    _sinew,
    UsageError,
    SinewError,
    "Bad arguments: an unknown option or a value out of range (the CLI's exit code 2)."
);
