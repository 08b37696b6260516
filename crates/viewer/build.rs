//! `hrtao --version` names the commit it was built from: `HRTAO_GIT_COMMIT` from `git rev-parse`, left unset when
//! the sources are not a git checkout of hrtao (a tarball) or git is missing.
use std::path::PathBuf;
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
}

fn main() {
    println!("cargo:rerun-if-env-changed=HRTAO_GIT_COMMIT");
    if let Ok(commit) = std::env::var("HRTAO_GIT_COMMIT") {
        // A packager may name the commit of a tarball.
        println!("cargo:rustc-env=HRTAO_GIT_COMMIT={commit}");
        return;
    }
    // Only hrtao's own checkout counts (sources unpacked inside another repository have no commit of ours).
    let workspace = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("../..");
    let ours = git(&["rev-parse", "--show-toplevel"])
        .and_then(|top| std::fs::canonicalize(top).ok())
        .is_some_and(|top| std::fs::canonicalize(&workspace).is_ok_and(|w| w == top));
    let Some(commit) = git(&["rev-parse", "--short=12", "HEAD"]).filter(|_| ours) else {
        return;
    };
    println!("cargo:rustc-env=HRTAO_GIT_COMMIT={commit}");
    // Rebuild when HEAD moves: HEAD itself (a checkout), the branch it points at, and packed refs.
    if let Some(dir) = git(&["rev-parse", "--git-dir"]).map(PathBuf::from) {
        println!("cargo:rerun-if-changed={}", dir.join("HEAD").display());
    }
    if let Some(common) = git(&["rev-parse", "--git-common-dir"]).map(PathBuf::from) {
        println!("cargo:rerun-if-changed={}", common.join("packed-refs").display());
        if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
            println!("cargo:rerun-if-changed={}", common.join(branch).display());
        }
    }
}
