//! Finds Debian's libode (double precision, at least 0.16) and generates raw
//! bindings for `ode/ode.h` into `OUT_DIR`.
//!
//! Lookup order, as in libsqlite3-sys and openssl-sys: `ODE_INCLUDE_DIR` /
//! `ODE_LIB_DIR` from the environment first (for a libode outside the system
//! paths), then pkg-config.

use std::env;
use std::panic;
use std::path::PathBuf;

const MIN_VERSION: &str = "0.16";

/// Where the headers are and whether pkg-config vouched for double precision.
struct Found {
    include_dirs: Vec<PathBuf>,
}

fn main() {
    for var in ["ODE_INCLUDE_DIR", "ODE_LIB_DIR", "ODE_STATIC"] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let found = match (env::var_os("ODE_INCLUDE_DIR"), env::var_os("ODE_LIB_DIR")) {
        (Some(include), Some(lib)) => from_env(PathBuf::from(include), PathBuf::from(lib)),
        (None, None) => from_pkg_config(),
        _ => panic!(
            "ode-sys: set both ODE_INCLUDE_DIR and ODE_LIB_DIR, or neither (then pkg-config is used)"
        ),
    };
    for dir in &found.include_dirs {
        // Exported to dependents as DEP_ODE_INCLUDE (thanks to `links = "ode"`).
        println!("cargo:include={}", dir.display());
    }
    generate_bindings(&found);
}

fn from_env(include: PathBuf, lib: PathBuf) -> Found {
    println!("cargo:rustc-link-search=native={}", lib.display());
    let kind = if env::var_os("ODE_STATIC").is_some() {
        // A static libode is C++ inside; its runtime must come along.
        println!("cargo:rustc-link-lib=dylib=stdc++");
        "static"
    } else {
        "dylib"
    };
    println!("cargo:rustc-link-lib={kind}=ode");
    Found {
        include_dirs: vec![include],
    }
}

fn from_pkg_config() -> Found {
    let library = match pkg_config::Config::new()
        .atleast_version(MIN_VERSION)
        .probe("ode")
    {
        Ok(library) => library,
        Err(err @ pkg_config::Error::Command { .. }) => panic!(
            "ode-sys: could not run pkg-config ({err}).\n\
             Install it with `apt-get install pkg-config` (Debian package `pkg-config`)."
        ),
        Err(err) => panic!(
            "ode-sys: libode >= {MIN_VERSION} was not found by pkg-config ({err}).\n\
             Install it with `apt-get install libode-dev` (Debian package `libode-dev`), \
             or point ODE_INCLUDE_DIR and ODE_LIB_DIR at another build."
        ),
    };
    // dReal must be f64: every binding below and every number in the project
    // assumes it. Debian's libode-dev is the double build; the single-precision
    // variant would silently change the physics.
    match pkg_config::get_variable("ode", "precision") {
        Ok(p) if p == "dDOUBLE" => {}
        Ok(p) => panic!(
            "ode-sys: the installed libode is built with precision `{p}`, but pushlearn needs \
             double precision (dDOUBLE). Install Debian's `libode-dev`."
        ),
        Err(err) => panic!("ode-sys: pkg-config has no `precision` variable for ode ({err})"),
    }
    Found {
        include_dirs: library.include_paths,
    }
}

fn generate_bindings(found: &Found) {
    // The #error turns a single-precision header into a build failure instead
    // of bindings whose dReal is f32; this also covers the ODE_INCLUDE_DIR path
    // where pkg-config was not asked. We never define dDOUBLE ourselves.
    let wrapper = "#include <ode/ode.h>\n\
                   #ifndef dDOUBLE\n\
                   #error \"libode headers are not double precision (dDOUBLE); install Debian's libode-dev\"\n\
                   #endif\n";
    let mut builder = bindgen::Builder::default()
        .header_contents("ode_wrapper.h", wrapper)
        // `d[A-Z].*` (rather than `d.*`) keeps ODE's names and leaves out the C
        // library's (`div`, `drand48`, and the duplicate FP_* constants of math.h).
        .allowlist_function("d[A-Z].*")
        .allowlist_type("d[A-Z].*")
        .allowlist_var("d[A-Z].*")
        .layout_tests(true)
        .derive_default(true)
        .derive_debug(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
    for dir in &found.include_dirs {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }

    // bindgen panics when it cannot load libclang; turn that into advice.
    let generated = panic::catch_unwind(panic::AssertUnwindSafe(move || builder.generate()));
    let bindings = match generated {
        Ok(Ok(bindings)) => bindings,
        Ok(Err(err)) => panic!(
            "ode-sys: bindgen could not process ode/ode.h ({err}).\n\
             Is Debian's `libode-dev` (double precision) installed?"
        ),
        Err(_) => panic!(
            "ode-sys: bindgen could not load libclang.\n\
             Install it with `apt-get install libclang-dev` (Debian package `libclang-dev`), \
             or set LIBCLANG_PATH."
        ),
    };
    let Some(out_dir) = env::var_os("OUT_DIR") else {
        panic!("ode-sys: cargo did not set OUT_DIR");
    };
    let out = PathBuf::from(out_dir).join("bindings.rs");
    if let Err(err) = bindings.write_to_file(&out) {
        panic!("ode-sys: cannot write {}: {err}", out.display());
    }
}
