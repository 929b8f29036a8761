//! Links CMU PocketSphinx, from one of two places:
//!
//! - **Debian's** `libpocketsphinx` and `libsphinxbase` 0.8 (`apt-get install
//!   libpocketsphinx-dev`), when installed: the library every figure of faceanim's lip sync was
//!   measured with;
//! - **its sources**, where Debian's is not there (macOS, Windows, other Linux): PocketSphinx
//!   5.1.0 as its PyPI source package ships it (C sources and US English models, BSD), unpacked
//!   by `scripts/setup.sh libraries` into `FACEANIM_POCKETSPHINX_SOURCE` or the user's data
//!   folder (`$XDG_DATA_HOME/faceanim/pocketsphinx-5.1.0`, `~/.local/share/…`,
//!   `%LOCALAPPDATA%\faceanim\…`), compiled here by `cc` and linked statically; its models
//!   are read from that folder at run time. `FACEANIM_POCKETSPHINX_SOURCE` set chooses the
//!   sources even where Debian's library is installed, and a folder there that does not
//!   build stops the build with its name.
//!
//! Where neither is found (or `FACEANIM_NO_POCKETSPHINX` is set) the crate builds without the
//! recogniser and its decoder says how to install it, so the rest of faceanim builds and runs
//! on any machine.
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

/// The source package's folder name.
const SOURCE_FOLDER: &str = "pocketsphinx-5.1.0";

fn main() {
    println!("cargo::rustc-check-cfg=cfg(pocketsphinx)");
    println!("cargo::rustc-check-cfg=cfg(pocketsphinx_source)");
    println!("cargo::rerun-if-env-changed=FACEANIM_NO_POCKETSPHINX");
    println!("cargo::rerun-if-env-changed=FACEANIM_POCKETSPHINX_SOURCE");
    if std::env::var_os("FACEANIM_NO_POCKETSPHINX").is_some() {
        println!(
            "cargo::warning=FACEANIM_NO_POCKETSPHINX is set: lip sync will say the recogniser is missing"
        );
        return;
    }
    let chosen = std::env::var_os("FACEANIM_POCKETSPHINX_SOURCE")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from);
    if let Some(source) = &chosen {
        // Asked for by name: a folder that cannot be built is an error, not a quiet fallback.
        watch_source(source);
        let built = if is_source(source) {
            build_source(source)
        } else {
            Err(format!(
                "{}: holds no PocketSphinx 5.1 sources (src/pocketsphinx.c, include/pocketsphinx.h, model/en-us/en-us/mdef)",
                source.display()
            ))
        };
        if let Err(e) = built {
            eprintln!("FACEANIM_POCKETSPHINX_SOURCE: {e}");
            std::process::exit(1);
        }
        return;
    }
    let found: Option<[PathBuf; 2]> = DIRS.iter().find_map(|d| {
        let libraries = ["libpocketsphinx.so", "libsphinxbase.so"].map(|l| Path::new(d).join(l));
        libraries.iter().all(|l| l.exists()).then_some(libraries)
    });
    if let Some(libraries) = &found {
        for library in libraries {
            println!("cargo::rerun-if-changed={}", library.display());
        }
        println!("cargo::rustc-cfg=pocketsphinx");
        println!("cargo::rustc-link-lib=dylib=pocketsphinx");
        println!("cargo::rustc-link-lib=dylib=sphinxbase");
        return;
    }
    for dir in DIRS {
        println!("cargo::rerun-if-changed={dir}/libpocketsphinx.so");
    }
    if let Some(source) = default_source() {
        watch_source(&source);
        if is_source(&source) {
            if let Err(e) = build_source(&source) {
                println!("cargo::warning={e}: lip sync will say the recogniser is missing");
            }
            return;
        }
    }
    println!(
        "cargo::warning=CMU PocketSphinx not found: lip sync will say so (scripts/setup.sh libraries installs it)"
    );
}

/// The folder `scripts/setup.sh libraries` unpacks the source package into.
fn default_source() -> Option<PathBuf> {
    let var = |name: &str| {
        println!("cargo::rerun-if-env-changed={name}");
        std::env::var_os(name)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    var("XDG_DATA_HOME")
        .or_else(|| var("HOME").map(|home| home.join(".local").join("share")))
        .or_else(|| var("LOCALAPPDATA"))
        .map(|base| base.join("faceanim").join(SOURCE_FOLDER))
}

/// Rebuild when the sources appear, change or go.
fn watch_source(source: &Path) {
    println!(
        "cargo::rerun-if-changed={}",
        source.join("src").join("pocketsphinx.c").display()
    );
}

fn is_source(source: &Path) -> bool {
    source.join("src").join("pocketsphinx.c").is_file()
        && source.join("src").join("CMakeLists.txt").is_file()
        && source.join("include").join("pocketsphinx.h").is_file()
        && source
            .join("model")
            .join("en-us")
            .join("en-us")
            .join("mdef")
            .is_file()
}

/// The C files of the library, as its own build lists them (`add_library(pocketsphinx …)` in
/// `src/CMakeLists.txt`).
fn library_sources(source: &Path) -> Vec<PathBuf> {
    let list =
        std::fs::read_to_string(source.join("src").join("CMakeLists.txt")).unwrap_or_default();
    let Some(start) = list.find("add_library(pocketsphinx") else {
        return Vec::new();
    };
    let body = &list[start + "add_library(pocketsphinx".len()..];
    let body = &body[..body.find(')').unwrap_or(body.len())];
    body.split_whitespace()
        .filter(|f| f.ends_with(".c"))
        .map(|f| source.join("src").join(f))
        .collect()
}

/// Compiles the library from `source` and points the crate at its models.
fn build_source(source: &Path) -> Result<(), String> {
    let files = library_sources(source);
    if files.is_empty() || files.iter().any(|f| !f.is_file()) {
        return Err(format!(
            "{}: src/CMakeLists.txt does not list the library's C files as PocketSphinx 5.1 does",
            source.display()
        ));
    }
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    let windows = std::env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "windows");
    let big_endian = std::env::var("CARGO_CFG_TARGET_ENDIAN").is_ok_and(|e| e == "big");
    let long = if windows { 4 } else { 8 };
    // The two headers CMake writes from `config.h.in` and `sphinx_config.h.in`, for the
    // platforms Rust targets.
    let mut config = format!(
        "#define DEFAULT_RADIX 12\n#define HAVE_LONG_LONG 1\n#define HAVE_SNPRINTF 1\n#define HAVE_SYS_STAT_H 1\n#define HAVE_SYS_TYPES_H 1\n#define HAVE_STDINT_H 1\n#define SIZEOF_LONG {long}\n#define SIZEOF_LONG_LONG 8\n#define PACKAGE_NAME \"PocketSphinx\"\n#define PACKAGE_VERSION \"5.1.0\"\n#define PACKAGE_STRING \"PocketSphinx 5.1.0\"\n#define PACKAGE_TARNAME \"pocketsphinx-5.1.0\"\n"
    );
    if !windows {
        config
            .push_str("#define HAVE_UNISTD_H 1\n#define HAVE_POPEN 1\n#define HAVE_INTTYPES_H 1\n");
    }
    if big_endian {
        config.push_str("#define WORDS_BIGENDIAN 1\n");
    }
    let public = format!(
        "#define DEFAULT_RADIX 12\n#ifndef HAVE_STDINT_H\n#define HAVE_STDINT_H 1\n#endif\n#define SIZEOF_LONG {long}\n#ifndef HAVE_LONG_LONG\n#define HAVE_LONG_LONG 1\n#endif\n#define SIZEOF_LONG_LONG 8\n"
    );
    let include = out.join("include").join("pocketsphinx");
    let written = std::fs::create_dir_all(&include)
        .and_then(|()| std::fs::write(out.join("config.h"), config))
        .and_then(|()| std::fs::write(include.join("sphinx_config.h"), public));
    written.map_err(|e| format!("{}: {e}", out.display()))?;
    let mut build = cc::Build::new();
    build
        .files(&files)
        .include(&out)
        .include(out.join("include"))
        .include(source.join("src"))
        .include(source.join("include"))
        .define("HAVE_CONFIG_H", None)
        .define("POCKETSPHINX_EXPORTS", None)
        .define("SPHINXBASE_EXPORTS", None)
        // Its random numbers (dithering) per thread, as its own build has them by default: a
        // line's decoders run on threads of their own.
        .define("PS_USE_THREAD_LOCAL_RNG", None)
        // The library's own code, not ours: its warnings are its maintainers'.
        .warnings(false)
        .opt_level(2);
    build.try_compile("pocketsphinx").map_err(|e| {
        format!(
            "compiling PocketSphinx from {} failed: {e}",
            source.display()
        )
    })?;
    if !windows {
        println!("cargo::rustc-link-lib=m");
    }
    let model = source.join("model").join("en-us");
    println!(
        "cargo::rustc-env=FACEANIM_POCKETSPHINX_MODEL={}",
        model.display()
    );
    println!("cargo::rustc-cfg=pocketsphinx");
    println!("cargo::rustc-cfg=pocketsphinx_source");
    Ok(())
}
