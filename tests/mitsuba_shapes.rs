//! The shapes of issue 37 held to Mitsuba 3 itself: `serialized` meshes (positions, normals and texture
//! coordinates as Mitsuba reads them: scenes/references/serialized.json, made by serialized.py beside it).

use std::path::Path;

use glam::{Vec2, Vec3};
use ppm_vk_engine::Scene;

const REFERENCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/references");

/// A Mitsuba scene in `dir` with a camera, a light and `body`.
fn xml_scene(dir: &Path, name: &str, body: &str) -> std::path::PathBuf {
    let text = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\
         <transform name=\"to_world\"><lookat origin=\"0, 1, 9\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\
         <film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/></film>\
         </sensor>\n<shape type=\"rectangle\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"90\"/>\
         <translate y=\"5\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>\
         </shape>\n{body}\n</scene>\n"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn json(name: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(format!("{REFERENCES}/{name}")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn floats(v: &serde_json::Value) -> Vec<f32> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect()
}

/// Each shape of each file, read by ppm-vk with the to_world Mitsuba read it with, has Mitsuba's
/// positions, normals (the file's for the quad, Mitsuba's computed ones for the tetrahedron) and texture
/// coordinates at every corner of every triangle (ppm-vk renumbers the vertices in their order of use).
#[test]
fn serialized_meshes_read_as_mitsuba_reads_them() {
    let doc = json("serialized.json");
    let matrix: Vec<String> = floats(&doc["to_world_matrix"]).iter().map(|x| x.to_string()).collect();
    let dir = std::env::temp_dir().join(format!("ppm-vk-mitsuba-shapes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shapes = doc["shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 4);
    for shape in shapes {
        let file = shape["file"].as_str().unwrap();
        let index = shape["shape_index"].as_u64().unwrap();
        let body = format!(
            r#"<shape type="serialized"><string name="filename" value="{REFERENCES}/serialized/{file}"/>
               <integer name="shape_index" value="{index}"/>
               <transform name="to_world"><matrix value="{}"/></transform>
               <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#,
            matrix.join(" ")
        );
        let s = Scene::load(xml_scene(&dir, "s.xml", &body)).unwrap_or_else(|e| panic!("{file}@{index}: {e:#}"));
        let m = &s.meshes[0];
        let vec3 = |key: &str, i: usize| {
            let v = floats(&shape[key][i]);
            Vec3::new(v[0], v[1], v[2])
        };
        let faces = shape["faces"].as_array().unwrap();
        assert_eq!(m.indices.len(), faces.len(), "{file}@{index}");
        let normals = m.normals.as_ref().expect("vertex normals");
        let uvs = m.uvs.as_ref().expect("texture coordinates");
        for (k, (ours, theirs)) in m.indices.iter().zip(faces).enumerate() {
            for (j, &i) in ours.iter().enumerate() {
                let t = theirs[j].as_u64().unwrap() as usize;
                let (p, n, uv) = (vec3("positions", t), vec3("normals", t), floats(&shape["uvs"][t]));
                let at = format!("{file}@{index} triangle {k} corner {j}");
                assert!(
                    m.positions[i as usize].distance(p) < 1e-5,
                    "{at}: {} vs {p}",
                    m.positions[i as usize]
                );
                assert!(
                    normals[i as usize].distance(n) < 1e-5,
                    "{at}: normal {} vs {n}",
                    normals[i as usize]
                );
                assert!(uvs[i as usize].distance(Vec2::new(uv[0], uv[1])) < 1e-6, "{at}: uv");
            }
        }
        s.validate().unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
}
