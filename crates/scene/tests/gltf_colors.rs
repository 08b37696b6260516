//! base_color = material baseColorFactor × mean(COLOR_0).

mod common;

use common::{base64, no_progress, temp_dir, TRI};
use hrtao_scene::load;

fn write(dir: &std::path::Path, name: &str, material: bool) -> std::path::PathBuf {
    let mut bin = Vec::new();
    for p in TRI {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    // u8 normalized RGBA: mean = (255, 0, 51, 255)/255 -> (1, 0, 0.2, 1)
    bin.extend_from_slice(&[255, 0, 0, 255, 255, 0, 51, 255, 255, 0, 102, 255]);
    let (mat, mref) = if material {
        (
            r#""materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.5,1,1,0.5]}}],"#,
            r#","material":0"#,
        )
    } else {
        ("", "")
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},{mat}
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
 {{"bufferView":1,"componentType":5121,"normalized":true,"count":3,"type":"VEC4"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}}{mref}}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
        bin.len(),
        base64(&bin)
    );
    let p = dir.join(name);
    std::fs::write(&p, json).unwrap();
    p
}

fn close(a: [f32; 4], b: [f32; 4]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6)
}

#[test]
fn vertex_colour_mean_times_material_factor() {
    let dir = temp_dir("colors");
    let s = load(write(&dir, "c.gltf", true).to_str().unwrap(), &mut no_progress()).unwrap();
    let c = s.meshes[0].primitives[0].base_color;
    assert!(close(c, [0.5, 0.0, 0.2, 0.5]), "{c:?}");
    let s = load(
        write(&dir, "nomat.gltf", false).to_str().unwrap(),
        &mut no_progress(),
    )
    .unwrap();
    let c = s.meshes[0].primitives[0].base_color;
    assert!(close(c, [1.0, 0.0, 0.2, 1.0]), "{c:?}");
    let _ = std::fs::remove_dir_all(dir);
}
