//! A large image rendered tile by tile (background screenshots) equals the image rendered whole: every tile
//! pixel gets the full image's ray, the background gradient and the feature edges continue across the seams.
mod common;
use common::*;
use hrtao_core::tile::TileGrid;
use hrtao_core::{AoSettings, Mode, Primary, SceneGpu};
use hrtao_scene::glam::Vec3;

#[test]
fn tiles_assemble_into_the_whole_image() {
    let gpu = gpu();
    let scene = floor_with_part(
        "box",
        vec![
            quad(Vec3::new(0.0, 0.0, 2.0), Vec3::X * 2.0, Vec3::Y * 2.0),
            quad(Vec3::new(0.0, -2.0, 1.0), Vec3::X * 2.0, Vec3::Z),
            quad(Vec3::new(-2.0, 0.0, 1.0), Vec3::Y * 2.0, Vec3::Z),
        ],
        Vec3::new(3.0, 1.0, 0.0),
    );
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    // Looking across the floor: the horizon and the background gradient are in view.
    let perspective = z_up_camera_fov([-4.0, -14.0, 5.0], [3.0, 1.0, 1.0], 60.0, (160, 90));
    let ortho = perspective.with_projection(hrtao_core::camera::Projection::Orthographic);
    for cam in [perspective, ortho] {
        let settings = {
            let mut s = AoSettings::default();
            s.display.mode = Mode::NoAo;
            s.display.edges = true;
            s
        };
        let mut whole = Headless::new(&gpu, cam.width, cam.height, settings.clone()).unwrap();
        whole.render(&sg, scene.f(), &cam).unwrap();
        let expected = whole.read_rgba().unwrap();

        let grid = TileGrid::new(cam.width, cam.height, 2500, 3);
        assert!(grid.len() >= 6, "{} tiles", grid.len());
        let (tw, th) = grid.render_size();
        // Both primary visibilities: rays through the tile's frame, and the rasteriser's off-axis frustum.
        for primary in [Primary::RayQuery, Primary::Raster] {
            let mut r = Headless::new(&gpu, tw, th, settings.clone()).unwrap();
            r.set_primary(primary);
            let mut image = vec![0u8; expected.len()];
            for i in 0..grid.len() {
                r.tile = Some(grid.tile(i));
                r.render(&sg, scene.f(), &cam).unwrap();
                grid.copy_inner(i, &r.read_rgba().unwrap(), &mut image);
            }
            let differ = expected
                .chunks_exact(4)
                .zip(image.chunks_exact(4))
                .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 2))
                .count();
            let sky = expected.chunks_exact(4).filter(|p| p[2] > p[0] + 8).count();
            println!(
                "{:?}, {primary:?}: {} tiles of {tw}x{th}: {differ} pixels differ, {sky} background pixels",
                cam.projection,
                grid.len()
            );
            if !cam.is_orthographic() {
                assert!(sky > 500, "the background gradient is in view ({sky} pixels)");
            }
            // Rays computed through another (mathematically equal) frame, or a rasterised edge, may flip a
            // pixel on a silhouette.
            assert!(
                differ <= 10,
                "{:?}, {primary:?}: {differ} pixels differ between the tiled and the whole image",
                cam.projection
            );
        }
    }
    assert_clean(&gpu);
}
