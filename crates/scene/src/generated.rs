//! The demo meshes of `scenes/meshes/` that crates/scene-gen writes (the large ones are not in git): their
//! names, and the command that writes them. Data only: the generator lives in that dev-only crate, which
//! takes its list of files from here; the library needs the list for the hint in a missing mesh's error.

use std::path::Path;

/// The command that writes the demo meshes.
pub const COMMAND: &str = "cargo run --release -p ppm-vk-scene-gen --bin gen_scenes";

/// One generated file.
pub struct DemoFile {
    /// File name inside the meshes directory.
    pub name: &'static str,
    /// Committed to git (small); the others are ignored by git and written on demand.
    pub committed: bool,
}

pub const FILES: &[DemoFile] = &[
    DemoFile {
        name: "cornell-box.obj",
        committed: true,
    },
    DemoFile {
        name: "cornell-box.mtl",
        committed: true,
    },
    DemoFile {
        name: "furnace-sphere.obj",
        committed: true,
    },
    DemoFile {
        name: "furnace-sphere.mtl",
        committed: true,
    },
    DemoFile {
        name: "smooth-sphere.obj",
        committed: true,
    },
    DemoFile {
        name: "glass-sphere.obj",
        committed: false,
    },
    DemoFile {
        name: "water.obj",
        committed: false,
    },
    DemoFile {
        name: "dense-sphere.obj",
        committed: false,
    },
    DemoFile {
        name: "water.mtl",
        committed: false,
    },
    DemoFile {
        name: "glass-on-table.obj",
        committed: false,
    },
    DemoFile {
        name: "glass-on-table.mtl",
        committed: false,
    },
    DemoFile {
        name: "gold-ring.obj",
        committed: false,
    },
    // scenes/interior.xml: a staircase hall, one file per material.
    DemoFile {
        name: "interior-shell.obj",
        committed: false,
    },
    DemoFile {
        name: "interior-wood.obj",
        committed: false,
    },
    DemoFile {
        name: "interior-glass.obj",
        committed: false,
    },
    DemoFile {
        name: "interior-metal.obj",
        committed: false,
    },
];

/// True when `path` names a file the generator writes but git does not hold (for a hint in the
/// error of a missing file).
pub fn is_generated(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str());
    FILES.iter().any(|f| !f.committed && Some(f.name) == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_files_git_does_not_hold_are_generated() {
        assert!(is_generated(Path::new("x/water.obj")));
        assert!(!is_generated(Path::new("x/cornell-box.obj")));
    }
}
