//! `hrtao render`: load, build, render K frames headless, write images and statistics.
use std::time::Instant;

use anyhow::{anyhow, Result};
use hrtao_core::{imageio, FrameDesc, FrameReport};

use crate::cli::{DeviceArgs, RenderArgs};
use crate::common::{load_scene, open_gpu, progress, write_json};
use crate::setup::{self, Device, Installed, SetupInputs};

#[derive(serde::Serialize)]
struct RenderStats<'a> {
    device: &'a hrtao_core::DeviceInfo,
    scene: String,
    unique_triangles: u64,
    instanced_triangles: u64,
    instances: usize,
    meshes: usize,
    width: u32,
    height: u32,
    settings: &'a hrtao_core::AoSettings,
    load_ms: f64,
    build: &'a hrtao_core::accel::BuildStats,
    frames: &'a [FrameReport],
    total_rays: u64,
    render_ms: f64,
    validation_messages: u32,
    /// The section planes (scene coordinates) and the instances they keep, cross and cut away.
    sections: &'a hrtao_core::Sections,
    section_sides: [usize; 3],
    /// The last frame against --ao-reference / --light-reference.
    #[serde(skip_serializing_if = "Option::is_none")]
    ao_error: Option<hrtao_core::metrics::AoError>,
    #[serde(skip_serializing_if = "Option::is_none")]
    light_error: Option<hrtao_core::metrics::LightError>,
}

/// A reference image of the render's size (`w` × `h`), read by `read`; an error names the file.
fn reference<T>(
    path: &std::path::Path,
    (w, h): (u32, u32),
    read: impl Fn(&std::path::Path) -> hrtao_core::Result<(u32, u32, Vec<T>)>,
) -> Result<Vec<T>> {
    let (rw, rh, data) = read(path)?;
    if (rw, rh) != (w, h) {
        anyhow::bail!("{}: a {rw}×{rh} reference for a {w}×{h} render", path.display());
    }
    Ok(data)
}

/// A scene loaded, set up and installed on a device as `render` does it, ready for its frames (`hrtao thumbnail`
/// renders through it too).
pub struct Ready {
    /// The scene as loaded (path or `gen:` spec; the bundled scene's file).
    pub spec: String,
    pub scene: hrtao_scene::Scene,
    pub load_ms: f64,
    pub prepared: setup::Prepared,
    pub settings: hrtao_core::AoSettings,
    pub installed: Installed,
}

/// Loads `args`' scene while the device opens, applies the setup rules and the AO options, and installs both.
pub fn ready(args: &RenderArgs) -> Result<Ready> {
    let inputs = SetupInputs::from_render(args);
    let spec = inputs.load_spec();
    // The device opens and the renderer makes its pipelines while the scene loads (a STEP file loads in a worker
    // process; on a CPU device both take a core).
    let early = {
        let device = args.device.clone();
        std::thread::spawn(move || Device::open(&device))
    };
    // Everything that can fail before the device is needed; the device thread is joined whatever happens (no
    // exit while that thread is inside the driver).
    let prepared = (|| -> Result<_> {
        let (mut scene, load_ms) = load_scene(&spec)?;
        let mut prepared = setup::prepare(&inputs, &scene)?;
        if let Some(storey) = &args.plan {
            crate::plan::apply(&mut scene, &mut prepared, storey)?;
        }
        let mut settings = args.ao.settings(prepared.radius)?;
        // The sky's zenith is the scene's up axis (--up, the camera file's, or the scene's default).
        settings.light.sky_up = prepared.up;
        settings.validate().map_err(|e| anyhow::anyhow!(e))?;
        if (args.light_out.is_some() || args.light_reference.is_some())
            && !(settings.light.sky_light && settings.display.mode == hrtao_core::Mode::Hrtao)
        {
            anyhow::bail!(
                "--light-out and --light-reference need the sky light: give --environment (and the HRTAO mode)"
            );
        }
        Ok((scene, load_ms, prepared, settings))
    })();
    let device = early.join().map_err(|_| anyhow!("the device thread panicked"))?;
    let (scene, load_ms, prepared, settings) = prepared?;
    let installed = device?.install(&scene, &prepared, &settings)?;
    Ok(Ready {
        spec,
        scene,
        load_ms,
        prepared,
        settings,
        installed,
    })
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let set_at_frame = crate::cli::set_at_frame(&args.set_at_frame)?;
    let Ready {
        spec,
        scene,
        load_ms,
        prepared,
        mut settings,
        installed:
            Installed {
                gpu,
                scene_gpu,
                mut renderer,
                ..
            },
    } = ready(args)?;
    let (camera, sections) = (prepared.camera, &prepared.sections);
    let t0 = Instant::now();
    let mut frames = Vec::new();
    let bar = progress(args.frames as u64, "rendering");
    for i in 0..args.frames {
        for (_, json) in set_at_frame.iter().filter(|(k, _)| *k == i) {
            // As the panel applies a change: the new settings from the next frame on.
            settings = settings
                .with_overrides(json)
                .map_err(|e| anyhow!("--set-at-frame {i}: {e}"))?;
            log::info!("settings after frame {i}: {json}");
        }
        let report = renderer.render(&FrameDesc::new(&scene_gpu, scene.f(), camera, &settings))?;
        log::info!(
            "frame {i}: {:.1} ms wall, {:.1} ms GPU, {} rays{}",
            report.wall_ms,
            report.gpu_total_ms,
            report.rays,
            if settings.display.mode.uses_hash() {
                format!(
                    ", {} cells ({:.1}% load), {} failed inserts",
                    report.occupied_cells,
                    report.load_factor * 100.0,
                    report.failed_inserts
                )
            } else {
                String::new()
            }
        );
        if report.non_finite > 0 {
            log::warn!(
                "frame {i}: the device produced {} non-finite values (NaN or infinite); replaced before they \
                 reached the map or the image",
                report.non_finite
            );
        }
        frames.push(report);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let render_ms = t0.elapsed().as_secs_f64() * 1e3;
    let (w, h) = renderer.size();
    if let Some(out) = &args.out {
        let rgba = renderer.read_rgba()?;
        imageio::write_png(out, w, h, &rgba)?;
        log::info!("wrote {}", out.display());
    }
    if let Some(out) = &args.ao_out {
        let ao = renderer.read_ao()?;
        imageio::write_ao(out, w, h, &ao)?;
        log::info!("wrote {}", out.display());
    }
    if let Some(out) = &args.light_out {
        let light = renderer.read_light()?;
        imageio::write_rgb(out, w, h, &light)?;
        log::info!("wrote {}", out.display());
    }
    let ao_error = match &args.ao_reference {
        Some(path) => {
            let reference = reference(path, (w, h), imageio::read_ao)?;
            Some(hrtao_core::metrics::ao_error(&renderer.read_ao()?, &reference))
        }
        None => None,
    };
    let light_error = match &args.light_reference {
        Some(path) => {
            let reference = reference(path, (w, h), imageio::read_rgb)?;
            Some(hrtao_core::metrics::light_error(
                &renderer.read_light()?,
                &reference,
            ))
        }
        None => None,
    };
    for (what, mae) in [
        ("AO", ao_error.map(|e| e.mae)),
        ("sky light", light_error.map(|e| e.mae)),
    ] {
        if let Some(mae) = mae {
            log::info!("{what} MAE against the reference: {mae:.4}");
        }
    }
    let validation_messages = gpu.validation_messages();
    if let Some(path) = &args.stats {
        let stats = RenderStats {
            device: &gpu.info,
            scene: spec.clone(),
            unique_triangles: scene.unique_triangle_count(),
            instanced_triangles: scene.instanced_triangle_count(),
            instances: scene.instances.len(),
            meshes: scene.meshes.len(),
            width: w,
            height: h,
            settings: &settings,
            load_ms,
            build: &scene_gpu.stats,
            total_rays: frames.iter().map(|f| f.rays).sum(),
            frames: &frames,
            render_ms,
            validation_messages,
            sections,
            section_sides: scene_gpu.section_sides,
            ao_error,
            light_error,
        };
        write_json(path, &stats)?;
    }
    if validation_messages > 0 {
        log::warn!("the validation layer reported {validation_messages} messages");
    }
    Ok(())
}

/// `hrtao devices`: every Vulkan device, whether hrtao can use it, which one it opens and by what rule.
pub fn list_devices(d: &DeviceArgs) -> Result<()> {
    let options = hrtao_core::ContextOptions {
        device: d.device.clone(),
        ray_backend: d.ray_backend,
        ..Default::default()
    };
    let devices = hrtao_core::context::list_devices(&options)?;
    print!("{}", devices_report(&devices, d.device.as_deref()));
    if !devices.iter().any(|x| x.chosen) {
        anyhow::bail!("no usable Vulkan device with ray queries or ray-tracing pipelines");
    }
    // The chosen device opened as every command opens it: its driver and API version.
    let gpu = open_gpu(d)?;
    println!(
        "opened: {} ({}), driver {}, Vulkan {}, rays traced by {}",
        gpu.info.name,
        gpu.info.kind,
        gpu.info.driver,
        gpu.info.api_version,
        gpu.info.ray_backend.name()
    );
    Ok(())
}

/// The text of `hrtao devices` before the chosen device is opened.
pub fn devices_report(devices: &[hrtao_core::context::DeviceListing], filter: Option<&str>) -> String {
    let mut out = format!("Vulkan devices ({}):\n", devices.len());
    for (i, x) in devices.iter().enumerate() {
        let state = match (&x.problem, x.chosen) {
            (_, true) => "usable, chosen".to_string(),
            (None, false) => "usable".to_string(),
            (Some(p), false) => format!("not usable: {p}"),
        };
        out.push_str(&format!("  {i}: {} ({}): {state}\n", x.name, x.kind));
    }
    let rule = "hrtao takes the usable device of the best kind (discrete GPU, integrated GPU, virtual GPU, \
                other, CPU), the first one listed among equals";
    let filter = filter
        .map(|f| format!(" whose name contains `{f}` (--device / HRTAO_DEVICE)"))
        .unwrap_or_default();
    match devices.iter().find(|x| x.chosen) {
        Some(x) => out.push_str(&format!("chosen: {} ({}): {rule}{filter}.\n", x.name, x.kind)),
        None => out.push_str(&format!("chosen: none; {rule}{filter}.\n")),
    }
    out
}
