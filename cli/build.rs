//! Links the `sinew` binary against the static C++ runtime (libstdc++.a) where the C++ compiler
//! has one, instead of libstdc++.so.
//!
//! meshoptimizer (C++, through the `meshopt` crate) needs only `operator new` and `delete` from it,
//! but loading the shared library costs every process about 0.3 ms (its 1,600-odd symbol
//! relocations and start-up code): `sinew --version` 1.50 -> 1.22 ms on the reference machine
//! (docs/performance.md, "Process start"), a fifth of the time a small convert spends outside its
//! work. A linker finds the first `libstdc++.*` along its search path for `meshopt`'s
//! `-lstdc++`, so a directory holding only the archive, searched first, selects it. Where the
//! compiler has no archive (some distributions package it apart) or the target is not GNU/Linux,
//! nothing changes: the binary links the shared library as before.

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=CXX");
    println!("cargo:rerun-if-env-changed=SINEW_SHARED_LIBSTDCXX");
    let linux_gnu = std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux")
        && std::env::var("CARGO_CFG_TARGET_ENV").as_deref() == Ok("gnu");
    // An escape hatch for packagers who want the shared runtime.
    if !linux_gnu || std::env::var_os("SINEW_SHARED_LIBSTDCXX").is_some() {
        return;
    }
    let Some(archive) = static_libstdcxx() else {
        return;
    };
    let Some(out) = std::env::var_os("OUT_DIR").map(PathBuf::from) else {
        return;
    };
    let dir = out.join("static-libstdcxx");
    let link = dir.join("libstdc++.a");
    let _ = std::fs::remove_file(&link);
    if std::fs::create_dir_all(&dir).is_err()
        || std::os::unix::fs::symlink(&archive, &link).is_err()
    {
        return;
    }
    // For the `sinew` binary only: a search directory given to the linker applies to every
    // `-l` wherever it stands, and libraries (the Python extension links this crate into a
    // shared object) keep the shared runtime.
    println!("cargo:rustc-link-arg-bins=-L{}", dir.to_string_lossy());
}

/// The C++ compiler's `libstdc++.a`, if it has one (`-print-file-name` answers the bare name
/// when it does not).
fn static_libstdcxx() -> Option<PathBuf> {
    let compilers = std::env::var("CXX")
        .ok()
        .into_iter()
        .chain(["c++".to_string(), "g++".to_string()]);
    for cxx in compilers {
        let Ok(output) = Command::new(&cxx)
            .arg("-print-file-name=libstdc++.a")
            .output()
        else {
            continue;
        };
        let path = String::from_utf8_lossy(&output.stdout).trim().to_string();
        let path = Path::new(&path);
        if output.status.success() && path.is_absolute() && path.is_file() {
            return Some(path.to_path_buf());
        }
    }
    None
}
