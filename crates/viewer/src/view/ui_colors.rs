//! egui's colours as egui-ash-renderer takes them over our swapchain, without a `pow` per pixel.
//!
//! egui's vertex colours and textures hold sRGB-encoded values, blended in that space. egui-ash-renderer works in
//! linear light: its vertex shader decodes vertex colours (`pow(c, 2.2)`), textures are uploaded as
//! `R8G8B8A8_SRGB` (the sampler decodes them by the sRGB curve), and on a UNORM target such as our swapchain
//! (it holds the composite's sRGB bytes) its fragment shader encodes every fragment again (`pow(c, 1 / 2.2)`).
//! On a CPU rasteriser that last `pow` costs more than the rest of egui's drawing. So the layer tells the renderer
//! its target is sRGB (no encoding per fragment) and hands it colours encoded once more, by the inverse of each
//! decoding: the shader's decode then gives back egui's own values, and fragments are egui's values blended as egui
//! blends them (which is what the vendored egui-ash drew). On an `_SRGB` swapchain the target encodes, and only the
//! vertex shader's gamma 2.2 (not the sRGB curve) needs undoing.
use std::sync::OnceLock;

/// 8-bit tables of the encodings (the inverses of the renderer's decodings, per kind of target).
struct Tables {
    /// UNORM target: `round(255 (c / 255)^(1 / 2.2))`, undone by the vertex shader's `pow(c, 2.2)`.
    vertex: [u8; 256],
    /// UNORM target: the sRGB curve, undone by sampling an `_SRGB` texture.
    texel: [u8; 256],
    /// `_SRGB` target: the vertex shader's `pow(c, 2.2)` is not the sRGB curve the target encodes by (egui's
    /// dark panel fill would come out 7 levels darker); `(srgb_decode(c))^(1 / 2.2)` makes the two cancel.
    /// Textures need nothing there: the sampler decodes and the target encodes by the same curve.
    vertex_srgb: [u8; 256],
}

fn srgb_encode(c: f64) -> f64 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(c: f64) -> f64 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let table = |f: fn(f64) -> f64| std::array::from_fn(|i| (f(i as f64 / 255.0) * 255.0).round() as u8);
        Tables {
            vertex: table(|c| c.powf(1.0 / 2.2)),
            texel: table(srgb_encode),
            vertex_srgb: table(|c| srgb_decode(c).powf(1.0 / 2.2)),
        }
    })
}

fn encode(c: egui::Color32, table: &[u8; 256]) -> egui::Color32 {
    let [r, g, b, a] = c.to_array();
    egui::Color32::from_rgba_premultiplied(table[r as usize], table[g as usize], table[b as usize], a)
}

/// Encodes the meshes' vertex colours for the renderer's vertex shader (alpha unchanged), for a UNORM target or
/// an `_SRGB` one (`srgb_target`).
pub fn encode_vertices(primitives: &mut [egui::ClippedPrimitive], srgb_target: bool) {
    let t = if srgb_target {
        &tables().vertex_srgb
    } else {
        &tables().vertex
    };
    for p in primitives {
        if let egui::epaint::Primitive::Mesh(mesh) = &mut p.primitive {
            for v in &mut mesh.vertices {
                v.color = encode(v.color, t);
            }
        }
    }
}

/// The image of a texture change, its texels encoded for an `_SRGB` upload (alpha unchanged), for a UNORM
/// target (an `_SRGB` target takes egui's texels as they are).
pub fn encode_texture(delta: &egui::epaint::ImageDelta) -> egui::epaint::ImageDelta {
    let t = &tables().texel;
    let egui::ImageData::Color(image) = &delta.image;
    let mut image = (**image).clone();
    for p in &mut image.pixels {
        *p = encode(*p, t);
    }
    egui::epaint::ImageDelta {
        image: egui::ImageData::Color(std::sync::Arc::new(image)),
        ..delta.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The renderer's decodings, as its shaders and the sampler compute them.
    fn shader_decode(c: u8) -> f64 {
        (c as f64 / 255.0).powf(2.2) * 255.0
    }

    fn sampler_decode(c: u8) -> f64 {
        255.0 * srgb_decode(c as f64 / 255.0)
    }

    /// What an `_SRGB` target stores of a vertex colour: the shader's decoding, then the sRGB curve.
    fn srgb_target(c: u8) -> f64 {
        255.0 * srgb_encode((c as f64 / 255.0).powf(2.2))
    }

    /// Every 8-bit value comes back from the renderer's decoding within 1.25 levels (half a step of the encoded
    /// byte times the decoding's slope, at most 2.4), and 0 and 255 exactly.
    #[test]
    fn each_encoding_is_undone_by_the_renderers_decoding() {
        let t = tables();
        for c in 0..=255u8 {
            for (back, name) in [
                (shader_decode(t.vertex[c as usize]), "vertex"),
                (sampler_decode(t.texel[c as usize]), "texel"),
                (srgb_target(t.vertex_srgb[c as usize]), "vertex on an sRGB target"),
            ] {
                let err = (back - c as f64).abs();
                assert!(err <= 1.25, "{name} {c}: back as {back:.2}");
            }
        }
        for c in [0u8, 255] {
            assert_eq!(t.vertex[c as usize], c);
            assert_eq!(t.texel[c as usize], c);
            assert_eq!(t.vertex_srgb[c as usize], c);
        }
    }

    #[test]
    fn alpha_and_callbacks_pass_unchanged() {
        let mut mesh = egui::Mesh::default();
        mesh.colored_vertex(
            egui::pos2(0.0, 0.0),
            egui::Color32::from_rgba_premultiplied(10, 128, 250, 77),
        );
        let mut prims = vec![egui::ClippedPrimitive {
            clip_rect: egui::Rect::EVERYTHING,
            primitive: egui::epaint::Primitive::Mesh(mesh),
        }];
        encode_vertices(&mut prims, false);
        let egui::epaint::Primitive::Mesh(m) = &prims[0].primitive else {
            unreachable!()
        };
        let [r, g, b, a] = m.vertices[0].color.to_array();
        assert_eq!(a, 77);
        assert!(r > 10 && g > 128 && b > 250 - 5, "encoded brighter: {r} {g} {b}");
    }
}
