//! Links Debian's SUNDIALS (libsundials-dev: 6.x on Debian 12, 7.x built with MPI on Debian 13)
//! and generates the bindings stickslip uses with one bindgen pass over the system headers.
//!
//! Why not `sundials-sys`: its build script passes no MPI include folder to bindgen, so on an
//! MPI-enabled system SUNDIALS (Debian 13) it cannot read `sundials_types.h` (which includes
//! `<mpi.h>`) and silently falls back to building its vendored SUNDIALS; nor can it express
//! `SUN_COMM_NULL`, which is OpenMPI's `MPI_COMM_NULL` macro (the address of
//! `ompi_mpi_comm_null`). Its wrapper header also binds no ARKODE function, so we already ran
//! bindgen here for ARKStep. One pass over the system headers, with the MPI flags when SUNDIALS
//! needs them, serves both versions and can never pick up a vendored copy.
//!
//! CVODE comes from CVODES (`libsundials_cvodes`, header `cvodes/cvodes.h`), never from
//! `libsundials_cvode`: CVODES is a superset of CVODE's API with the same function names
//! (`CVodeCreate`, `CVode`, `CVodeInit`, ...) and its own memory layout, so linking both would
//! bind every `CVode*` call to whichever library the dynamic linker meets first, and a
//! CVODES-only call (`CVodeSensInit`) on memory made by CVODE's `CVodeCreate` would corrupt it.
//! One library serves the plain CVODE wrapper and the forward sensitivities.
//!
//! Emits `cfg(sundials7)` for the 7.x API; the version differences stay in
//! crates/ode/src/sundials/. Cargo runs this script for crates/ode, the one crate that calls
//! SUNDIALS. Fails loudly, naming what is actually missing and the Debian package that
//! provides it.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

fn fail(what: &str, fix: &str) -> ! {
    panic!("\n\nstickslip build: {what}\n  fix: {fix}\n  stickslip never builds a vendored SUNDIALS.\n\n");
}

const FIX_SUNDIALS: &str = "`apt-get install -y libsundials-dev` (or run `bash tools/deps.sh`, which the README commands call)";

/// What sundials_config.h says about the installed SUNDIALS.
struct Config {
    version: String,
    major: u32,
    mpi: bool,
}

fn include_dir() -> PathBuf {
    let candidates: Vec<PathBuf> =
        env::var_os("SUNDIALS_INCLUDE_DIR").map(|d| vec![PathBuf::from(d)]).unwrap_or_else(|| {
            vec![PathBuf::from("/usr/include"), PathBuf::from("/usr/local/include")]
        });
    let needed = ["sundials/sundials_config.h", "cvodes/cvodes.h", "arkode/arkode_arkstep.h"];
    for dir in &candidates {
        if needed.iter().all(|h| dir.join(h).is_file()) {
            return dir.clone();
        }
    }
    let missing: Vec<String> = candidates
        .iter()
        .flat_map(|d| needed.iter().map(move |h| d.join(h)))
        .filter(|p| !p.is_file())
        .map(|p| p.display().to_string())
        .collect();
    fail(&format!("the SUNDIALS headers are missing: {}", missing.join(", ")), FIX_SUNDIALS);
}

/// Reads the version and the MPI switch from sundials_config.h.
fn read_config(inc: &Path) -> Config {
    let path = inc.join("sundials/sundials_config.h");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| fail(&format!("cannot read {}: {e}", path.display()), FIX_SUNDIALS));
    let define = |name: &str| {
        text.lines()
            .find_map(|l| {
                l.trim()
                    .strip_prefix("#define ")?
                    .strip_prefix(name)?
                    .strip_prefix(' ')
                    .map(str::trim)
            })
            .map(|v| v.trim_matches('"').to_string())
    };
    let version = define("SUNDIALS_VERSION").unwrap_or_else(|| {
        fail(&format!("{} has no SUNDIALS_VERSION", path.display()), FIX_SUNDIALS)
    });
    let major: u32 = version.split('.').next().and_then(|m| m.parse().ok()).unwrap_or(0);
    if major != 6 && major != 7 {
        fail(
            &format!("found SUNDIALS {version} in {}; stickslip supports the 6.x (Debian 12) and 7.x (Debian 13) series", path.display()),
            "install Debian 12's or 13's libsundials-dev, or point SUNDIALS_INCLUDE_DIR / SUNDIALS_LIBRARY_DIR at a 6.x or 7.x installation",
        );
    }
    let mpi = define("SUNDIALS_MPI_ENABLED").is_some_and(|v| v == "1");
    Config { version, major, mpi }
}

fn library_dir(config: &Config) -> PathBuf {
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(d) = env::var_os("SUNDIALS_LIBRARY_DIR") {
        candidates.push(d.into());
    }
    candidates.extend(
        [
            format!("/usr/lib/{arch}-linux-gnu"),
            "/usr/lib".into(),
            "/usr/lib64".into(),
            "/usr/local/lib".into(),
        ]
        .map(PathBuf::from),
    );
    let needed: Vec<String> = libraries(config).iter().map(|l| format!("lib{l}.so")).collect();
    for dir in &candidates {
        if needed.iter().all(|l| dir.join(l).exists()) {
            return dir.clone();
        }
    }
    let first = &candidates[0];
    let missing: Vec<&str> =
        needed.iter().filter(|l| !first.join(l).exists()).map(String::as_str).collect();
    fail(
        &format!(
            "SUNDIALS {} shared libraries not found: {} missing from {} (also searched {:?})",
            config.version,
            missing.join(", "),
            first.display(),
            &candidates[1..]
        ),
        FIX_SUNDIALS,
    );
}

/// The SUNDIALS libraries stickslip links.
fn libraries(config: &Config) -> Vec<&'static str> {
    let mut libs = vec![
        // CVODE and its forward sensitivities; never also sundials_cvode (see the header).
        "sundials_cvodes",
        "sundials_arkode",
        "sundials_nvecserial",
        "sundials_sunmatrixdense",
        "sundials_sunlinsoldense",
    ];
    if config.major >= 7 {
        // SUNContext, SUNLogger and the error handlers moved into sundials_core in 7.0.
        libs.push("sundials_core");
    }
    libs
}

/// Include folders and link flags of the MPI implementation SUNDIALS was built with.
#[derive(Default)]
struct Mpi {
    include: Vec<PathBuf>,
    link_dirs: Vec<PathBuf>,
    libs: Vec<String>,
    source: String,
}

/// Finds MPI the Debian way: pkg-config (`mpi-c` from mpi-default-dev, then `ompi-c`,
/// `mpich`), else the compiler wrapper (`mpicc --showme:compile/link` for OpenMPI, `mpicc
/// -show` for MPICH). Accepts the first that provides a folder holding mpi.h.
fn find_mpi(config: &Config) -> Mpi {
    let mut tried = Vec::new();
    for name in ["mpi-c", "ompi-c", "mpich"] {
        match pkg_config::Config::new().cargo_metadata(false).env_metadata(false).probe(name) {
            Ok(lib) => {
                let mpi = Mpi {
                    include: lib.include_paths,
                    link_dirs: lib.link_paths,
                    libs: lib.libs,
                    source: format!("pkg-config {name}"),
                };
                if has_mpi_h(&mpi) {
                    return mpi;
                }
                tried.push(format!("pkg-config {name} (no mpi.h in {:?})", mpi.include));
            }
            Err(_) => tried.push(format!("pkg-config {name} (not found)")),
        }
    }
    let wrapper = env::var("MPICC").unwrap_or_else(|_| "mpicc".into());
    let run = |args: &[&str]| -> Option<Vec<String>> {
        let out = Command::new(&wrapper).args(args).output().ok().filter(|o| o.status.success())?;
        Some(String::from_utf8_lossy(&out.stdout).split_whitespace().map(String::from).collect())
    };
    let flags = match (run(&["--showme:compile"]), run(&["--showme:link"])) {
        (Some(mut compile), Some(link)) => {
            compile.extend(link);
            Some(compile)
        }
        _ => run(&["-show"]),
    };
    if let Some(flags) = flags {
        let mut mpi = Mpi { source: format!("{wrapper} flags"), ..Mpi::default() };
        for f in flags {
            if let Some(d) = f.strip_prefix("-I") {
                mpi.include.push(d.into());
            } else if let Some(d) = f.strip_prefix("-L") {
                mpi.link_dirs.push(d.into());
            } else if let Some(l) = f.strip_prefix("-l") {
                mpi.libs.push(l.into());
            }
        }
        if has_mpi_h(&mpi) {
            return mpi;
        }
        tried.push(format!("{wrapper} (no mpi.h in {:?})", mpi.include));
    } else {
        tried.push(format!("{wrapper} (not found)"));
    }
    fail(
        &format!(
            "SUNDIALS {} was built with MPI (SUNDIALS_MPI_ENABLED 1), so its sundials_types.h includes <mpi.h>, \
             but no MPI include folder holding mpi.h was found; tried: {}",
            config.version,
            tried.join("; ")
        ),
        "`apt-get install -y mpi-default-dev pkg-config` (Debian's MPI headers and their pkg-config file; \
         libsundials-dev normally pulls them in), or set MPICC to your MPI compiler wrapper",
    );
}

fn has_mpi_h(mpi: &Mpi) -> bool {
    mpi.include.iter().any(|d| d.join("mpi.h").is_file())
}

/// Bindings for everything src/sundials/ calls: context (and on 7.x logger and error
/// handlers), serial vectors, dense matrix and linear solver, CVODES (CVODE with forward
/// sensitivities), ARKStep and ARKODE.
fn bindings(inc: &Path, config: &Config, mpi: &Mpi, out: &Path) {
    let mut header = String::from(
        "#include <sundials/sundials_context.h>\n#include <sundials/sundials_version.h>\n\
         #include <nvector/nvector_serial.h>\n#include <sunmatrix/sunmatrix_dense.h>\n\
         #include <sunlinsol/sunlinsol_dense.h>\n#include <cvodes/cvodes.h>\n\
         #include <arkode/arkode_arkstep.h>\n",
    );
    if config.major >= 7 {
        header.push_str(
            "#include <sundials/sundials_logger.h>\n#include <sundials/sundials_errors.h>\n",
        );
    }
    let functions = "SUNContext_.*|SUNLogger_.*|SUNDIALSGetVersion|N_VNew_Serial|N_VDestroy\
                     |SUNDenseMatrix|SUNDenseMatrix_Data|SUNMatDestroy|SUNLinSol_Dense|SUNLinSolFree\
                     |CVode.*|ARKStep.*|ARKode.*";
    let mut builder = bindgen::Builder::default()
        .header_contents("stickslip_sundials.h", &header)
        .clang_arg(format!("-I{}", inc.display()))
        .allowlist_function(functions)
        .allowlist_var("CV_.*|ARK_.*|ARKODE_.*|SUN_LOGLEVEL_.*")
        // The serial vector's content, read directly as nvector_serial.h's NV_DATA_S does.
        .allowlist_type("ARKODE_.*|SUNLogLevel|_N_VectorContent_Serial")
        // Only ever behind pointers (the *PrintAllStats functions); glibc's layout has bitfields.
        .opaque_type("FILE|_IO_FILE")
        // SUNDIALS' flags and return codes are C ints (`CV_BDF`, `ARK_SUCCESS`, ...).
        .default_macro_constant_type(bindgen::MacroTypeVariation::Signed)
        .layout_tests(false)
        .derive_debug(false);
    for dir in &mpi.include {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }
    let generated =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || builder.generate()));
    match generated {
        Ok(Ok(bindings)) => bindings
            .write_to_file(out)
            .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", out.display()), "check the target directory")),
        Ok(Err(e)) => fail(
            &format!("bindgen could not parse the SUNDIALS {} headers in {}: {e}", config.version, inc.display()),
            "the compiler error above names the missing header; install the Debian package that provides it",
        ),
        Err(_) => fail(
            "bindgen could not load libclang (needed to read the SUNDIALS headers)",
            "`apt-get install -y libclang-dev` (or run `bash tools/deps.sh`)",
        ),
    }
}

/// SUNDIALS 7's `SUN_COMM_NULL` is a macro: 0 without MPI, `MPI_COMM_NULL` with it (for
/// OpenMPI the address of the `ompi_mpi_comm_null` object, which bindgen cannot translate). A
/// one-line C function returns whatever the headers define, compiled with SUNDIALS' own flags.
fn comm_null_shim(inc: &Path, mpi: &Mpi) {
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let source = out.join("stickslip_comm_null.c");
    std::fs::write(
        &source,
        "#include <sundials/sundials_types.h>\nSUNComm stickslip_sun_comm_null(void) { return SUN_COMM_NULL; }\n",
    )
    .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", source.display()), "check the target directory"));
    let mut build = cc::Build::new();
    build.file(&source).include(inc).warnings(true);
    for dir in &mpi.include {
        build.include(dir);
    }
    build.try_compile("stickslip_comm_null").unwrap_or_else(|e| {
        fail(&format!("cannot compile the SUN_COMM_NULL shim: {e}"), "`apt-get install -y gcc`")
    });
}

fn main() {
    // This script sits at the top of the repository and builds crates/ode (its Cargo.toml
    // says `build = "../../build.rs"`); Cargo reads the path relative to that crate.
    println!("cargo:rerun-if-changed=../../build.rs");
    for var in ["SUNDIALS_INCLUDE_DIR", "SUNDIALS_LIBRARY_DIR", "MPICC", "PKG_CONFIG_PATH"] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    println!("cargo::rustc-check-cfg=cfg(sundials7)");

    let inc = include_dir();
    let config = read_config(&inc);
    let lib = library_dir(&config);
    let mpi = if config.mpi { find_mpi(&config) } else { Mpi::default() };
    println!("cargo:rerun-if-changed={}", inc.join("sundials/sundials_config.h").display());
    println!("cargo:rustc-env=STICKSLIP_SUNDIALS_HEADER_VERSION={}", config.version);
    println!("cargo:rustc-env=STICKSLIP_SUNDIALS_LIBRARY_DIR={}", lib.display());
    println!(
        "cargo:rustc-env=STICKSLIP_SUNDIALS_MPI={}",
        if config.mpi { mpi.source.as_str() } else { "no" }
    );
    if config.major >= 7 {
        println!("cargo:rustc-cfg=sundials7");
    }

    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"))
        .join("sundials_bindings.rs");
    bindings(&inc, &config, &mpi, &out);
    if config.major >= 7 {
        comm_null_shim(&inc, &mpi);
    }

    println!("cargo:rustc-link-search=native={}", lib.display());
    for l in libraries(&config) {
        println!("cargo:rustc-link-lib=dylib={l}");
    }
    for dir in &mpi.link_dirs {
        println!("cargo:rustc-link-search=native={}", dir.display());
    }
    for l in &mpi.libs {
        println!("cargo:rustc-link-lib=dylib={l}");
    }
}
