//! Links Intel Embree (feature `embree`, on by default): finds its headers and library, compiles
//! the C shim in `sys/` and generates Rust bindings for the shim's own header. Without the
//! feature nothing is built here and the crate uses its built-in BVH alone.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "embree")]
    embree::build();
}

#[cfg(feature = "embree")]
mod embree {
    use std::env;
    use std::path::{Path, PathBuf};

    /// Where one Embree installation lives.
    struct Found {
        major: u32,
        include_dirs: Vec<PathBuf>,
        lib_dirs: Vec<PathBuf>,
        how: String,
    }

    const VARS: [&str; 3] = ["EMBREE_DIR", "EMBREE_INCLUDE_DIR", "EMBREE_LIB_DIR"];

    pub fn build() {
        for var in VARS {
            println!("cargo:rerun-if-env-changed={var}");
        }
        println!("cargo:rerun-if-changed=sys/shim.c");
        println!("cargo:rerun-if-changed=sys/shim.h");

        // Variables the user set on purpose come first: pkg-config would otherwise always find
        // the system's Embree 3 and an Embree 4 elsewhere could never be chosen.
        let found = from_env()
            .or_else(from_pkg_config)
            .or_else(from_system_paths)
            .unwrap_or_else(|| {
                panic!(
                    "\n\ntrilux: Intel Embree was not found (feature `embree` is on by default).\n\
                     Install it:   apt-get install -y libembree-dev libclang-dev pkg-config\n\
                     or point the build at it: EMBREE_DIR=/prefix (or EMBREE_INCLUDE_DIR and EMBREE_LIB_DIR).\n\
                     To build with the built-in BVH alone: cargo build --no-default-features\n\n"
                )
            });
        println!(
            "cargo:warning=trilux: using Embree {} ({})",
            found.major, found.how
        );

        let mut cc = cc::Build::new();
        cc.file("sys/shim.c")
            .define("TX_EMBREE_MAJOR", found.major.to_string().as_str())
            .opt_level(3)
            .warnings(true);
        for dir in &found.include_dirs {
            cc.include(dir);
        }
        cc.compile("trilux_shim");

        for dir in &found.lib_dirs {
            println!("cargo:rustc-link-search=native={}", dir.display());
        }
        println!("cargo:rustc-link-lib=embree{}", found.major);

        // The shim's header names no Embree type, so the bindings hold only trilux's own C API.
        let bindings = bindgen::Builder::default()
            .header("sys/shim.h")
            .allowlist_function("tx_.*")
            .allowlist_type("Tx.*")
            .allowlist_var("TX_.*")
            .layout_tests(false)
            .generate()
            .expect("bindgen failed on sys/shim.h (is libclang-dev installed?)");
        let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
        bindings
            .write_to_file(out.join("shim_bindings.rs"))
            .expect("cannot write the generated bindings");
    }

    fn header_major(include_dir: &Path) -> Option<u32> {
        [4, 3].into_iter().find(|major| {
            include_dir
                .join(format!("embree{major}/rtcore.h"))
                .is_file()
        })
    }

    fn from_pkg_config() -> Option<Found> {
        for major in [4, 3] {
            if let Ok(lib) = pkg_config::Config::new()
                .cargo_metadata(false)
                .probe(&format!("embree{major}"))
            {
                let mut include_dirs = lib.include_paths.clone();
                // Some .pc files point inside embreeN/; the shim includes <embreeN/rtcore.h>.
                include_dirs.extend(
                    lib.include_paths
                        .iter()
                        .filter_map(|p| p.parent().map(Path::to_path_buf)),
                );
                return Some(Found {
                    major,
                    include_dirs,
                    lib_dirs: lib.link_paths,
                    how: format!("pkg-config embree{major}"),
                });
            }
        }
        None
    }

    fn from_env() -> Option<Found> {
        let dir = env::var_os("EMBREE_DIR").map(PathBuf::from);
        let include = env::var_os("EMBREE_INCLUDE_DIR")
            .map(PathBuf::from)
            .or_else(|| dir.as_ref().map(|d| d.join("include")))?;
        let lib = env::var_os("EMBREE_LIB_DIR")
            .map(PathBuf::from)
            .or_else(|| dir.as_ref().map(|d| d.join("lib")));
        let major = header_major(&include).unwrap_or_else(|| {
            panic!(
                "\n\ntrilux: EMBREE_DIR / EMBREE_INCLUDE_DIR point at {}, which holds neither \
                 embree4/rtcore.h nor embree3/rtcore.h\n\n",
                include.display()
            )
        });
        Some(Found {
            major,
            include_dirs: vec![include],
            lib_dirs: lib.into_iter().collect(),
            how: "EMBREE_* variables".into(),
        })
    }

    fn from_system_paths() -> Option<Found> {
        [
            "/usr/include",
            "/usr/local/include",
            "/opt/homebrew/include",
        ]
        .into_iter()
        .map(PathBuf::from)
        .find_map(|include| {
            let major = header_major(&include)?;
            Some(Found {
                major,
                include_dirs: vec![include],
                lib_dirs: Vec::new(),
                how: "system include path".into(),
            })
        })
    }
}
