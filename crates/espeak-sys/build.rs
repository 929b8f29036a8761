//! Links Debian's libespeak-ng (`apt-get install libespeak-ng-dev`) when it is installed;
//! otherwise the crate builds without it and every call reports that the synthesiser is
//! missing, so the rest of faceanim builds and runs on any machine.
use std::path::Path;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(espeak)");
    println!("cargo::rerun-if-env-changed=FACEANIM_NO_ESPEAK");
    let dirs = [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib",
        "/usr/local/lib",
        "/opt/homebrew/lib",
    ];
    for dir in dirs {
        println!("cargo::rerun-if-changed={dir}/libespeak-ng.so");
    }
    let found = std::env::var_os("FACEANIM_NO_ESPEAK").is_none()
        && dirs.iter().any(|d| {
            Path::new(d).join("libespeak-ng.so").exists()
                || Path::new(d).join("libespeak-ng.dylib").exists()
        });
    if found {
        println!("cargo::rustc-cfg=espeak");
        println!("cargo::rustc-link-lib=dylib=espeak-ng");
    } else {
        println!(
            "cargo::warning=libespeak-ng not found: lip sync in languages other than English and alignment by synthesis will say so (apt-get install libespeak-ng-dev)"
        );
    }
}
