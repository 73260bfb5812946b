//! The `ppm-vk` binary on a scene with a mesh: loading warnings reach stderr, and the mesh renders.

mod common;

#[test]
fn render_prints_mesh_warnings_and_renders_the_mesh() {
    let dir = std::env::temp_dir().join(format!("ppm-vk-mesh-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // One good triangle, one degenerate; a glossy, textured material the engine approximates.
    std::fs::write(
        dir.join("cup.obj"),
        "mtllib cup.mtl\nusemtl porcelain\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 2\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("cup.mtl"),
        "newmtl porcelain\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNs 200\nillum 2\nmap_Kd cup.png\n",
    )
    .unwrap();
    let scene = dir.join("cup.toml");
    std::fs::write(
        &scene,
        "[camera]\neye = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov = 40.0\n\
         resolution = [8, 8]\n\n[materials.light]\nemission = [1.0, 1.0, 1.0]\n\n\
         [[quad]]\norigin = [0.0, 2.0, 0.0]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]\n\
         material = \"light\"\n\n[[mesh]]\nfile = \"cup.obj\"\n",
    )
    .unwrap();
    let run = common::bin()
        .args(["render", "--passes", "1", "--validate", "--out"])
        .arg(dir.join("out.png"))
        .arg(&scene)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    let written = dir.join("out.png").exists();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(run.status.success(), "the mesh scene did not render:\n{stderr}");
    assert!(written, "no image written");
    let obj = dir.join("cup.obj").display().to_string();
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(warnings.len(), 2, "{stderr}");
    assert!(
        warnings[0].starts_with(&format!("warning: {obj}: material \"porcelain\" ("))
            && warnings[0].contains("Ks/Ns glossy lobe ignored")
            && warnings[0].contains("map_Kd cup.png ignored"),
        "{stderr}"
    );
    assert_eq!(
        warnings[1],
        format!("warning: {obj}: 1 degenerate triangles dropped (zero area or a repeated vertex)")
    );
}
