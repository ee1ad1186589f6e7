//! Finds Debian's libmujoco-dev (MuJoCo 2.2) and generates raw bindings for
//! `mujoco/mujoco.h` into `OUT_DIR`.
//!
//! Debian ships no pkg-config file for MuJoCo, so the headers are looked for
//! in `MUJOCO_INCLUDE_DIR` (with `MUJOCO_LIB_DIR`, for a build outside the
//! system paths) or else in `/usr/include`. The version is read from the
//! header itself (`mjVERSION_HEADER`): the safe wrapper is written against
//! 2.2's API (its fixed-size virtual file system, for one), which 2.3 and 3.x
//! changed.

use std::env;
use std::panic;
use std::path::{Path, PathBuf};

/// `mjVERSION_HEADER / 10`: 2.2.x.
const WANTED_MINOR: u32 = 22;

fn main() {
    for var in ["MUJOCO_INCLUDE_DIR", "MUJOCO_LIB_DIR"] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let include = match (
        env::var_os("MUJOCO_INCLUDE_DIR"),
        env::var_os("MUJOCO_LIB_DIR"),
    ) {
        (Some(include), Some(lib)) => {
            println!(
                "cargo:rustc-link-search=native={}",
                Path::new(&lib).display()
            );
            PathBuf::from(include)
        }
        (None, None) => PathBuf::from("/usr/include"),
        _ => panic!(
            "mujoco-sys: set both MUJOCO_INCLUDE_DIR and MUJOCO_LIB_DIR, or neither \
             (then Debian's libmujoco-dev in /usr is used)"
        ),
    };
    let header = include.join("mujoco/mujoco.h");
    println!("cargo:rerun-if-changed={}", header.display());
    let text = match std::fs::read_to_string(&header) {
        Ok(text) => text,
        Err(err) => panic!(
            "mujoco-sys: cannot read {} ({err}).\n\
             Install MuJoCo 2.2 with `apt-get install libmujoco-dev` (Debian package \
             `libmujoco-dev`), or point MUJOCO_INCLUDE_DIR and MUJOCO_LIB_DIR at another build.",
            header.display()
        ),
    };
    let version = header_version(&text).unwrap_or_else(|| {
        panic!(
            "mujoco-sys: {} has no `#define mjVERSION_HEADER`; is it MuJoCo's? \
             Install Debian's `libmujoco-dev` (MuJoCo 2.2).",
            header.display()
        )
    });
    if version / 10 != WANTED_MINOR {
        panic!(
            "mujoco-sys: {} is MuJoCo {}.{}.{}, but pushlearn is written against MuJoCo 2.2 \
             (Debian bookworm's `libmujoco-dev`, 2.2.2). Install that package, or point \
             MUJOCO_INCLUDE_DIR and MUJOCO_LIB_DIR at a 2.2 build.",
            header.display(),
            version / 100,
            version / 10 % 10,
            version % 10
        );
    }
    println!("cargo:rustc-link-lib=dylib=mujoco");
    // Exported to dependents as DEP_MUJOCO_INCLUDE (thanks to `links`).
    println!("cargo:include={}", include.display());
    generate_bindings(&include);
}

/// The number of `#define mjVERSION_HEADER 222`.
fn header_version(text: &str) -> Option<u32> {
    text.lines().find_map(|line| {
        let rest = line.trim().strip_prefix("#define")?.trim_start();
        let value = rest.strip_prefix("mjVERSION_HEADER")?;
        value.trim().parse().ok()
    })
}

fn generate_bindings(include: &Path) {
    let builder = bindgen::Builder::default()
        .header_contents("mujoco_wrapper.h", "#include <mujoco/mujoco.h>\n")
        .clang_arg(format!("-I{}", include.display()))
        // MuJoCo's names: mj_*, mju_*, mjv_*, mjr_*, mjui_* functions and the
        // mj* types and constants; nothing of the C library.
        .allowlist_function("mj.*")
        .allowlist_type("mj.*")
        .allowlist_var("mj.*")
        .layout_tests(true)
        .derive_default(true)
        .derive_debug(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));

    // bindgen panics when it cannot load libclang; turn that into advice.
    let generated = panic::catch_unwind(panic::AssertUnwindSafe(move || builder.generate()));
    let bindings = match generated {
        Ok(Ok(bindings)) => bindings,
        Ok(Err(err)) => panic!(
            "mujoco-sys: bindgen could not process mujoco/mujoco.h ({err}).\n\
             Is Debian's `libmujoco-dev` installed?"
        ),
        Err(_) => panic!(
            "mujoco-sys: bindgen could not load libclang.\n\
             Install it with `apt-get install libclang-dev` (Debian package `libclang-dev`), \
             or set LIBCLANG_PATH."
        ),
    };
    let Some(out_dir) = env::var_os("OUT_DIR") else {
        panic!("mujoco-sys: cargo did not set OUT_DIR");
    };
    let out = PathBuf::from(out_dir).join("bindings.rs");
    if let Err(err) = bindings.write_to_file(&out) {
        panic!("mujoco-sys: cannot write {}: {err}", out.display());
    }
}
