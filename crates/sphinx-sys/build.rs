//! Links Debian's libpocketsphinx and libsphinxbase (`apt-get install libpocketsphinx-dev`)
//! when they are installed; otherwise the crate builds without them and its decoder reports
//! that the recogniser is missing, so the rest of faceanim builds and runs on any machine.
use std::path::Path;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(pocketsphinx)");
    println!("cargo::rerun-if-env-changed=FACEANIM_NO_POCKETSPHINX");
    let dirs = [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib",
        "/usr/local/lib",
    ];
    for dir in dirs {
        println!("cargo::rerun-if-changed={dir}/libpocketsphinx.so");
    }
    let found = std::env::var_os("FACEANIM_NO_POCKETSPHINX").is_none()
        && dirs.iter().any(|d| {
            Path::new(d).join("libpocketsphinx.so").exists()
                && Path::new(d).join("libsphinxbase.so").exists()
        });
    if found {
        println!("cargo::rustc-cfg=pocketsphinx");
        println!("cargo::rustc-link-lib=dylib=pocketsphinx");
        println!("cargo::rustc-link-lib=dylib=sphinxbase");
    } else {
        println!(
            "cargo::warning=libpocketsphinx not found: lip sync will say so (apt-get install libpocketsphinx-dev)"
        );
    }
}
