//! Embeds the git commit so that every JSON report names the code that produced it, and an
//! rpath to libtorch so that the binaries and tests run without LD_LIBRARY_PATH.

fn main() {
    let commit = std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_owned())
        .unwrap_or_else(|| "unknown".to_owned());
    println!("cargo:rustc-env=GRASPMAP_GIT_COMMIT={commit}");
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/refs/heads");

    // torch-sys (`links = "tch"`) tells its direct dependents where it found libtorch's
    // libraries (`.venv/libtorch/lib` through .cargo/config.toml). libtorch_cpu.so finds its own
    // dependencies (libc10, libgomp, and libcudart/libcupti under ../../nvidia/cu13/lib)
    // through its RPATH $ORIGIN/..., so this one directory is all the executables need.
    if let Ok(dir) = std::env::var("DEP_TCH_LIBTORCH_LIB") {
        let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
        if os == "linux" || os == "macos" {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}");
        }
    }
}
