//! A 3MF writer for tests (hrtao reads 3MF; it writes none): a scene's meshes as objects, its instances as build
//! items with their transforms, zipped with the package parts 3MF requires. Shared with the viewer's tests.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// Writes `scene` as a 3MF file at `path` in `unit` ("millimeter", ...), with the first primitive's colour of
/// each mesh as a base material.
pub fn write_3mf(scene: &hrtao_scene::Scene, path: &Path, unit: &str) {
    let mut xml = String::new();
    writeln!(xml, r#"<?xml version="1.0" encoding="UTF-8"?>"#).unwrap();
    writeln!(
        xml,
        r#"<model unit="{unit}" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02">"#
    )
    .unwrap();
    writeln!(xml, "<resources>").unwrap();
    // The `m:` prefix: the threemf crate reads base materials under it only.
    writeln!(xml, r#"<m:basematerials id="1">"#).unwrap();
    for m in &scene.meshes {
        let c = m.primitives[0].base_color;
        let srgb = |v: f32| {
            let v = v.clamp(0.0, 1.0);
            let e = if v <= 0.0031308 {
                v * 12.92
            } else {
                1.055 * v.powf(1.0 / 2.4) - 0.055
            };
            (e * 255.0).round() as u8
        };
        writeln!(
            xml,
            r##"<m:base name="{}" displaycolor="#{:02X}{:02X}{:02X}" />"##,
            m.name,
            srgb(c[0]),
            srgb(c[1]),
            srgb(c[2])
        )
        .unwrap();
    }
    writeln!(xml, "</m:basematerials>").unwrap();
    for (k, m) in scene.meshes.iter().enumerate() {
        writeln!(
            xml,
            r#"<object id="{}" type="model" name="{}" pid="1" pindex="{k}"><mesh><vertices>"#,
            k + 2,
            m.name
        )
        .unwrap();
        let mut base = 0u32;
        let mut tris = String::new();
        for p in &m.primitives {
            for v in &p.positions {
                writeln!(xml, r#"<vertex x="{}" y="{}" z="{}" />"#, v[0], v[1], v[2]).unwrap();
            }
            for t in p.indices.chunks_exact(3) {
                writeln!(
                    tris,
                    r#"<triangle v1="{}" v2="{}" v3="{}" />"#,
                    t[0] + base,
                    t[1] + base,
                    t[2] + base
                )
                .unwrap();
            }
            base += p.positions.len() as u32;
        }
        writeln!(xml, "</vertices><triangles>{tris}</triangles></mesh></object>").unwrap();
    }
    writeln!(xml, "</resources><build>").unwrap();
    for inst in &scene.instances {
        let c = inst.transform.to_cols_array();
        // Row vectors: m00 m01 m02 (the image of x), m10 m11 m12, m20 m21 m22, then the translation.
        let t = [
            c[0], c[1], c[2], c[4], c[5], c[6], c[8], c[9], c[10], c[12], c[13], c[14],
        ];
        let t: Vec<String> = t.iter().map(|v| v.to_string()).collect();
        writeln!(
            xml,
            r#"<item objectid="{}" transform="{}" />"#,
            inst.mesh + 2,
            t.join(" ")
        )
        .unwrap();
    }
    writeln!(xml, "</build></model>").unwrap();

    let file = std::fs::File::create(path).unwrap();
    let mut zip = zip::ZipWriter::new(file);
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("[Content_Types].xml", opts).unwrap();
    zip.write_all(
        br#"<?xml version="1.0" encoding="UTF-8"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>"#,
    )
    .unwrap();
    zip.start_file("_rels/.rels", opts).unwrap();
    zip.write_all(
        br#"<?xml version="1.0" encoding="UTF-8"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>"#,
    )
    .unwrap();
    zip.start_file("3D/3dmodel.model", opts).unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    zip.finish().unwrap();
}
