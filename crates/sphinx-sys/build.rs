//! Links Debian's libpocketsphinx and libsphinxbase (`apt-get install libpocketsphinx-dev`)
//! when they are installed; otherwise the crate builds without them and its decoder reports
//! that the recogniser is missing, so the rest of faceanim builds and runs on any machine.
//!
//! What Cargo watches: the libraries found, so that an upgrade or removal builds the crate
//! again and nothing else does; when none is found, the places they would be installed (a
//! path that does not exist is always stale to Cargo), so that the next build after
//! installing them links them.
use std::path::{Path, PathBuf};

const DIRS: [&str; 4] = [
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib",
    "/usr/local/lib",
];

fn main() {
    println!("cargo::rustc-check-cfg=cfg(pocketsphinx)");
    println!("cargo::rerun-if-env-changed=FACEANIM_NO_POCKETSPHINX");
    let found: Option<[PathBuf; 2]> = DIRS.iter().find_map(|d| {
        let libraries = ["libpocketsphinx.so", "libsphinxbase.so"].map(|l| Path::new(d).join(l));
        libraries.iter().all(|l| l.exists()).then_some(libraries)
    });
    match &found {
        Some(libraries) => {
            for library in libraries {
                println!("cargo::rerun-if-changed={}", library.display());
            }
        }
        None => {
            for dir in DIRS {
                println!("cargo::rerun-if-changed={dir}/libpocketsphinx.so");
            }
        }
    }
    if found.is_some() && std::env::var_os("FACEANIM_NO_POCKETSPHINX").is_none() {
        println!("cargo::rustc-cfg=pocketsphinx");
        println!("cargo::rustc-link-lib=dylib=pocketsphinx");
        println!("cargo::rustc-link-lib=dylib=sphinxbase");
    } else {
        println!(
            "cargo::warning=libpocketsphinx not found: lip sync will say so (apt-get install libpocketsphinx-dev)"
        );
    }
}
