//! Links Debian's SUNDIALS (libsundials-dev, 6.x) and generates the ARKStep bindings that
//! `sundials-sys` lacks. Fails loudly, naming the Debian packages to install, when the headers,
//! the libraries or libclang are missing; it never falls back to a vendored SUNDIALS.

use std::env;
use std::path::{Path, PathBuf};

const FIX: &str = "install Debian's SUNDIALS and libclang: \
                   `apt-get install -y libsundials-dev libclang-dev` \
                   (or run `bash tools/deps.sh`, which the README commands call)";

fn fail(what: &str) -> ! {
    panic!("\n\nstickslip build: {what}\n  fix: {FIX}\n  stickslip never builds a vendored SUNDIALS.\n\n");
}

fn include_dir() -> PathBuf {
    let candidates: Vec<PathBuf> = env::var_os("SUNDIALS_INCLUDE_DIR")
        .map(|d| vec![PathBuf::from(d)])
        .unwrap_or_else(|| vec![PathBuf::from("/usr/include"), PathBuf::from("/usr/local/include")]);
    for dir in &candidates {
        let needed = ["sundials/sundials_config.h", "cvode/cvode.h", "arkode/arkode_arkstep.h"];
        if needed.iter().all(|h| dir.join(h).is_file()) {
            return dir.clone();
        }
    }
    fail(&format!(
        "SUNDIALS headers (sundials/sundials_config.h, cvode/cvode.h, arkode/arkode_arkstep.h) \
         not found in {candidates:?}"
    ));
}

/// Reads `SUNDIALS_VERSION "x.y.z"` from sundials_config.h.
fn header_version(inc: &Path) -> String {
    let config = std::fs::read_to_string(inc.join("sundials/sundials_config.h"))
        .unwrap_or_else(|e| fail(&format!("cannot read sundials_config.h: {e}")));
    let version = config
        .lines()
        .find_map(|l| l.strip_prefix("#define SUNDIALS_VERSION "))
        .map(|v| v.trim().trim_matches('"').to_string())
        .unwrap_or_else(|| fail("sundials_config.h has no SUNDIALS_VERSION"));
    if !version.starts_with("6.") {
        fail(&format!(
            "found SUNDIALS {version}; stickslip targets the 6.x series shipped by Debian bookworm"
        ));
    }
    version
}

fn library_dir() -> PathBuf {
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(d) = env::var_os("SUNDIALS_LIBRARY_DIR") {
        candidates.push(d.into());
    }
    candidates.extend(
        [format!("/usr/lib/{arch}-linux-gnu"), "/usr/lib".into(), "/usr/lib64".into(), "/usr/local/lib".into()]
            .map(PathBuf::from),
    );
    for dir in &candidates {
        let needed = ["libsundials_cvode.so", "libsundials_arkode.so", "libsundials_nvecserial.so"];
        if needed.iter().all(|l| dir.join(l).exists()) {
            return dir.clone();
        }
    }
    fail(&format!(
        "SUNDIALS shared libraries (libsundials_cvode.so, libsundials_arkode.so) not found in {candidates:?}"
    ));
}

/// ARKStep/ERKStep bindings and `SUNDIALSGetVersion`, reusing sundials-sys's shared types (N_Vector, SUNMatrix, ...).
fn arkode_bindings(inc: &Path, out: &Path) {
    let shared_types = [
        "N_Vector", "_generic_N_Vector", "_generic_N_Vector_Ops", "N_Vector_Ops", "N_Vector_ID",
        "SUNContext", "_SUNContext", "SUNMatrix", "_generic_SUNMatrix", "_generic_SUNMatrix_Ops",
        "SUNMatrix_ID", "SUNLinearSolver", "_generic_SUNLinearSolver", "_generic_SUNLinearSolver_Ops",
        "SUNLinearSolver_Type", "SUNLinearSolver_ID", "SUNNonlinearSolver", "_generic_SUNNonlinearSolver",
        "_generic_SUNNonlinearSolver_Ops", "SUNNonlinearSolver_Type", "realtype", "sunrealtype",
        "sunindextype", "booleantype", "sunbooleantype", "SUNLogger", "_SUNLogger", "SUNProfiler",
        "_SUNProfiler", "FILE", "_IO_FILE", "SUNOutputFormat", "SUNComm",
    ];
    let mut builder = bindgen::Builder::default()
        .header_contents(
            "stickslip_arkode.h",
            "#include <sundials/sundials_version.h>\n#include <arkode/arkode_arkstep.h>\n#include <arkode/arkode_erkstep.h>\n",
        )
        .clang_arg(format!("-I{}", inc.display()))
        .allowlist_function("ARKStep.*|ERKStep.*|SUNDIALSGetVersion")
        .allowlist_var("ARK_.*|ARKODE_.*|ARKSTEP_.*")
        .allowlist_type("ARKODE_.*")
        .layout_tests(false);
    for ty in shared_types {
        builder = builder.blocklist_type(ty);
    }
    let generated = std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || builder.generate()));
    match generated {
        Ok(Ok(bindings)) => bindings
            .write_to_file(out)
            .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", out.display()))),
        Ok(Err(e)) => fail(&format!("bindgen could not parse the ARKODE headers: {e}")),
        Err(_) => fail("bindgen could not load libclang (needed to read the ARKODE headers)"),
    }
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=SUNDIALS_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=SUNDIALS_LIBRARY_DIR");

    let inc = include_dir();
    let version = header_version(&inc);
    let lib = library_dir();
    println!("cargo:rerun-if-changed={}", inc.join("sundials/sundials_config.h").display());
    println!("cargo:rustc-env=STICKSLIP_SUNDIALS_HEADER_VERSION={version}");
    println!("cargo:rustc-env=STICKSLIP_SUNDIALS_LIBRARY_DIR={}", lib.display());

    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("arkode_bindings.rs");
    arkode_bindings(&inc, &out);

    println!("cargo:rustc-link-search=native={}", lib.display());
    println!("cargo:rustc-link-lib=dylib=sundials_arkode");
}
