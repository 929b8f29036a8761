//! Links libespeak-ng (Debian's `apt-get install libespeak-ng-dev`, Homebrew's `brew install
//! espeak-ng`) when it is installed;
//! otherwise the crate builds without it and every call reports that the synthesiser is
//! missing, so the rest of faceanim builds and runs on any machine.
//!
//! What Cargo watches: the library found, so that an upgrade or removal builds the crate again
//! and nothing else does; when none is found, the places it would be installed (a path that
//! does not exist is always stale to Cargo), so that the next build after installing it links
//! it.
use std::path::Path;

const DIRS: [&str; 5] = [
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib",
    "/usr/local/lib",
    "/opt/homebrew/lib",
];

fn main() {
    println!("cargo::rustc-check-cfg=cfg(espeak)");
    println!("cargo::rerun-if-env-changed=FACEANIM_NO_ESPEAK");
    let found = DIRS.iter().find_map(|d| {
        ["libespeak-ng.so", "libespeak-ng.dylib"]
            .map(|l| Path::new(d).join(l))
            .into_iter()
            .find(|l| l.exists())
    });
    match &found {
        Some(library) => println!("cargo::rerun-if-changed={}", library.display()),
        None => {
            for dir in DIRS {
                println!("cargo::rerun-if-changed={dir}/libespeak-ng.so");
            }
        }
    }
    if found.is_some() && std::env::var_os("FACEANIM_NO_ESPEAK").is_none() {
        println!("cargo::rustc-cfg=espeak");
        // Where it was found: Homebrew's folder on Apple silicon is not one the linker
        // searches by itself.
        if let Some(dir) = found.as_deref().and_then(Path::parent) {
            println!("cargo::rustc-link-search=native={}", dir.display());
        }
        println!("cargo::rustc-link-lib=dylib=espeak-ng");
    } else {
        println!(
            "cargo::warning=libespeak-ng not found: lip sync in languages other than English and alignment by synthesis will say so (apt-get install libespeak-ng-dev)"
        );
    }
}
