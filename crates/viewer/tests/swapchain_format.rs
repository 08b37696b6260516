//! The swapchain's format rule, end to end in the window (Xvfb + lavapipe, which offers both kinds): an `_SRGB`
//! swapchain, written as such, presents the same picture as a UNORM one — the 3D view and egui's panel.
mod common;
use common::*;

/// The window capture of `hrtao view` with swapchain formats of one kind only (`HRTAO_SWAPCHAIN_FORMAT`).
fn capture(kind: &str) -> image::RgbImage {
    let dir = out_dir(&format!("swapchain-{kind}"));
    let shot = dir.join("window.png");
    // Whole frames (no slices, whose share depends on the machine's load: the view differed by 1.3 levels
    // in a loaded suite at 24 frames), so both runs end on the same frame of the still image.
    let args = [
        "--size",
        "900x400",
        "--mode",
        "none",
        "--frames",
        "24",
        "--no-auto-budget",
    ];
    let env = [
        ("HRTAO_SWAPCHAIN_FORMAT", kind),
        ("RUST_LOG", "info,hrtao::view::present=debug"),
    ];
    let stderr = scripted_run(
        &[&args[..], &["--screenshot-ui", shot.to_str().unwrap()]].concat(),
        &env,
    );
    let want = if kind == "srgb" { "_SRGB" } else { "_UNORM" };
    assert!(
        stderr
            .lines()
            .any(|l| l.contains("swapchain 900x400") && l.contains(want)),
        "a {want} swapchain:\n{stderr}"
    );
    image::open(&shot)
        .unwrap_or_else(|e| panic!("{}: {e}\n{stderr}", shot.display()))
        .to_rgb8()
}

/// Mean absolute difference of two captures over a rectangle, in 8-bit levels.
fn mean_diff(
    a: &image::RgbImage,
    b: &image::RgbImage,
    x: std::ops::Range<u32>,
    y: std::ops::Range<u32>,
) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for py in y {
        for px in x.clone() {
            let (p, q) = (a.get_pixel(px, py).0, b.get_pixel(px, py).0);
            sum += (0..3).map(|c| (p[c] as f64 - q[c] as f64).abs()).sum::<f64>() / 3.0;
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn an_srgb_swapchain_presents_what_a_unorm_one_does() {
    if !display_available() {
        return;
    }
    let unorm = capture("unorm");
    let srgb = capture("srgb");
    // The 3D view left of the view cube and above the toast: the composite's bytes, through an `_SRGB` internal
    // image on the sRGB swapchain.
    let view = mean_diff(&unorm, &srgb, 0..290, 0..350);
    // The panel's fill, right of its text: egui's colour through either encoding.
    let fill = mean_diff(&unorm, &srgb, 870..895, 60..400);
    // The panel's top lines (title, device, scene: the same text in both runs; lower lines show timings): egui
    // blends text in linear light on an `_SRGB` target, in sRGB values on a UNORM one, so the edges of the
    // glyphs differ a little; a doubly encoded panel would be ~70 levels off.
    let text = mean_diff(&unorm, &srgb, 430..860, 0..60);
    eprintln!("mean difference: view {view:.3}, panel fill {fill:.3}, panel text {text:.3} levels");
    assert!(view < 0.5, "view: {view}");
    assert!(fill < 1.0, "panel fill: {fill}");
    assert!(text < 4.0, "panel text: {text}");
}
