//! Files that point elsewhere (issue 11): references to devices, FIFOs, directories, places outside the
//! model's folder or sizes that lie give a clear error naming the reference within a bounded time and
//! memory; declared counts are checked against the memory limit before anything is read; loads can be
//! cancelled; valid external references still load.
#![cfg(feature = "hostile-corpus")]

mod common;

use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use common::{no_progress, split_glb, temp_dir, test_scene};
use hrtao_scene::hostile::{write_corpus, Expect, HostileCase};
use hrtao_scene::{load_with, LoadOptions, SceneError};

fn load(path: &Path, opts: &LoadOptions) -> Result<hrtao_scene::Scene, SceneError> {
    load_with(path.to_str().unwrap(), opts, &mut no_progress())
}

/// Peak resident memory of this test process (VmHWM), in bytes.
/// The hostile corpus's case `name` loaded with the default options.
fn load_case(cases: &[HostileCase], name: &str) -> Result<hrtao_scene::Scene, SceneError> {
    let c = cases.iter().find(|c| c.name == name).unwrap();
    load(&c.path, &LoadOptions::default())
}

fn peak_rss() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let kb: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .unwrap()
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .unwrap();
    kb * 1024
}

/// How long a load may take before the test calls it hung: a guard against a hang, never a speed check (the
/// tests check counts and errors; a 2-core machine under load may take seconds where an idle one takes
/// milliseconds).
const HANG_GUARD: Duration = Duration::from_secs(120);

#[test]
fn every_reference_case_ends_with_an_error_naming_the_reference() {
    let dir = temp_dir("refcorpus");
    let cases = write_corpus(&dir).unwrap();
    let with_refs: Vec<_> = cases.iter().filter(|c| c.reference.is_some()).collect();
    assert!(with_refs.len() >= 15, "{} reference cases", with_refs.len());
    for case in &cases {
        let t0 = Instant::now();
        let result = load(&case.path, &LoadOptions::default());
        let took = t0.elapsed();
        // A hang guard only (a reference followed to an endless file would never end): what the test checks is
        // the error naming the reference, which no loader can give after following it.
        assert!(took < HANG_GUARD, "{}: took {took:?}", case.name);
        match (case.expect, result) {
            (Expect::Image, Ok(s)) => assert!(s.unique_triangle_count() > 0, "{}", case.name),
            (Expect::Error, Err(e)) => {
                let msg = e.to_string();
                let file = case.path.file_name().unwrap().to_str().unwrap();
                assert!(msg.contains(file), "{}: names the file: {msg}", case.name);
                if let Some(r) = case.reference {
                    assert!(msg.contains(r), "{}: names the reference `{r}`: {msg}", case.name);
                }
                println!("{:40} {:>6.1} ms  {msg}", case.name, took.as_secs_f64() * 1e3);
            }
            (expect, r) => panic!("{}: expected {expect:?}, got {:?}", case.name, r.err()),
        }
    }
    let peak = peak_rss();
    assert!(peak < 1 << 30, "peak RSS {peak} bytes");
    println!(
        "peak RSS of the test process: {:.1} MiB",
        peak as f64 / (1 << 20) as f64
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn errors_say_what_the_reference_is() {
    let dir = temp_dir("refkinds");
    let cases = write_corpus(&dir).unwrap();
    let msg = |name: &str| load_case(&cases, name).unwrap_err().to_string();
    for (name, says) in [
        ("buffer_dev_zero", "outside the model's folder"),
        ("buffer_file_uri_dev_zero", "outside the model's folder"),
        ("buffer_etc_passwd", "outside the model's folder"),
        ("buffer_fifo", "FIFO"),
        ("buffer_symlink_to_dev_zero", "character device"),
        ("buffer_directory", "directory"),
        ("buffer_missing_file", "does not exist"),
        ("buffer_shorter_than_byte_length", "byteLength 72"),
        ("buffer_http_uri", "not supported"),
        ("model_is_a_fifo", "FIFO"),
        ("model_is_a_directory", "directory"),
        ("model_is_dev_zero", "character device"),
        ("obj_mtllib_fifo", "FIFO"),
        ("obj_mtllib_symlink_to_dev_zero", "character device"),
        ("obj_mtllib_dev_zero", "outside the model's folder"),
    ] {
        let m = msg(name);
        assert!(m.contains(says), "{name}: `{says}` expected in: {m}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// A buffer file longer than `byteLength` loads: only the declared bytes are read.
#[test]
fn a_longer_buffer_file_is_read_only_up_to_byte_length() {
    let dir = temp_dir("longer");
    let cases = write_corpus(&dir).unwrap();
    let c = cases.iter().find(|c| c.name == "buffer_external_valid").unwrap();
    let bin = dir.join("corner.bin");
    let mut bytes = std::fs::read(&bin).unwrap();
    let expected = load(&c.path, &LoadOptions::default()).unwrap();
    bytes.extend([0xffu8; 1000]);
    std::fs::write(&bin, bytes).unwrap();
    let s = load(&c.path, &LoadOptions::default()).unwrap();
    assert_eq!(s.bounds().min, expected.bounds().min);
    assert_eq!(s.bounds().max, expected.bounds().max);
    let _ = std::fs::remove_dir_all(dir);
}

/// A glTF whose one buffer is `uri` declaring `len` bytes, with a POSITION accessor of `count`.
fn gltf_with(dir: &Path, name: &str, uri: &str, len: u64, count: u64) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(
        &p,
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3"}}],
"bufferViews":[{{"buffer":0,"byteLength":{len}}}],"buffers":[{{"byteLength":{len},"uri":"{uri}"}}]}}"#
        ),
    )
    .unwrap();
    p
}

/// Declared counts are checked against the memory limit before any buffer is opened: the buffer here
/// is a FIFO, which would block a plain read forever.
#[test]
fn declared_geometry_over_the_memory_limit_is_too_large_before_reading() {
    let dir = temp_dir("declared");
    let cases = write_corpus(&dir).unwrap();
    assert!(cases.iter().any(|c| c.name == "buffer_fifo"));
    let p = gltf_with(&dir, "huge_count.gltf", "buffer_fifo.bin", 72, 1_000_000_000_000);
    let e = load(&p, &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, SceneError::TooLarge(_)), "{e:?}");
    let m = e.to_string();
    assert!(
        m.contains("huge_count.gltf") && m.contains("accessor counts"),
        "{m}"
    );

    // An exponential node DAG: 2^40 instances are refused without walking them.
    let levels = 40;
    let nodes: Vec<String> = (0..=levels)
        .map(|i| {
            if i < levels {
                format!(r#"{{"children":[{},{}]}}"#, i + 1, i + 1)
            } else {
                r#"{"mesh":0}"#.to_string()
            }
        })
        .collect();
    let text = std::fs::read_to_string(dir.join("buffer_external_valid.gltf")).unwrap();
    let start = text.find(r#""nodes":[{"#).unwrap();
    let end = start + text[start..].find("}]").unwrap() + 2;
    let dag = format!(
        "{}\"nodes\":[{}]{}",
        &text[..start],
        nodes.join(","),
        &text[end..]
    );
    let p = dir.join("dag.gltf");
    std::fs::write(&p, dag).unwrap();
    let t0 = Instant::now();
    let e = load(&p, &LoadOptions::default()).unwrap_err();
    // Refused by counting the instances the DAG expands to (the error says so), not by expanding them: a hang
    // guard only.
    assert!(t0.elapsed() < HANG_GUARD);
    assert!(
        matches!(&e, SceneError::TooLarge(m) if m.contains("instances")),
        "{e:?}"
    );

    // The same for OBJ: the v/f lines are counted first.
    let p = dir.join("faces.obj");
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for _ in 0..20_000 {
        obj.push_str("f 1 2 3\n");
    }
    std::fs::write(&p, obj).unwrap();
    let small = LoadOptions {
        max_memory: 256 << 10,
        ..Default::default()
    };
    let e = load(&p, &small).unwrap_err();
    assert!(
        matches!(&e, SceneError::TooLarge(m) if m.contains("faces.obj") && m.contains("v and f lines")),
        "{e:?}"
    );
    assert!(load(&p, &LoadOptions::default()).is_ok());
    let _ = std::fs::remove_dir_all(dir);
}

/// A real assembly as .gltf + external .bin (the rod, its GLB split) loads under a tight limit, the same as the
/// GLB, and not under a tiny one; the error names the file.
#[test]
fn external_buffer_loads_within_the_memory_limit() {
    let dir = temp_dir("external");
    let gltf = split_glb(&test_scene("rod"), &dir, "rod_external");
    let opts = LoadOptions {
        max_memory: LIMIT_TIGHT,
        ..Default::default()
    };
    let s = load(&gltf, &opts).unwrap();
    let glb = load(&test_scene("rod"), &opts).unwrap();
    assert_eq!(s.unique_triangle_count(), 5_412);
    assert_eq!(s.instances.len(), 29);
    assert_eq!(
        world_triangles(&s),
        world_triangles(&glb),
        "the same triangles as the GLB"
    );
    let tiny = LoadOptions {
        max_memory: LIMIT_TINY,
        ..Default::default()
    };
    let e = load(&gltf, &tiny).unwrap_err();
    assert!(matches!(e, SceneError::TooLarge(_)), "{e:?}");
    assert!(e.to_string().contains("rod_external"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Limits around the split rod's needs (measured: it loads from 362,943 bytes up, the GLB from 362,948).
const LIMIT_TIGHT: u64 = 1 << 20;
const LIMIT_TINY: u64 = 256 << 10;

/// Cancelling stops the load at the next chunk: a 1 GiB (sparse) buffer is not read to the end.
#[test]
fn cancel_stops_a_long_read() {
    let dir = temp_dir("cancel");
    let len: u64 = 1 << 30;
    std::fs::File::create(dir.join("big.bin"))
        .unwrap()
        .set_len(len)
        .unwrap();
    let p = gltf_with(&dir, "big.gltf", "big.bin", len, 3);
    let opts = LoadOptions::default();
    let cancel = opts.cancel.clone();
    let mut reports = Vec::new();
    let t0 = Instant::now();
    let r = load_with(p.to_str().unwrap(), &opts, &mut |pr| {
        reports.push(pr);
        if pr.stage == "read" && pr.total == len {
            cancel.store(true, Ordering::Relaxed);
        }
    });
    assert!(
        matches!(r, Err(SceneError::Cancelled(ref m)) if m.contains("big.gltf")),
        "{:?}",
        r.err()
    );
    // The cancel is seen at the next chunk (counted below); the time is a hang guard only.
    assert!(t0.elapsed() < HANG_GUARD, "{:?}", t0.elapsed());
    let read: Vec<_> = reports.iter().filter(|p| p.total == len).collect();
    assert_eq!(read.len(), 1, "one chunk read before the cancel was seen");
    assert!(read[0].done < len);

    // Cancelled before it starts: nothing is read.
    let opts = LoadOptions::default();
    opts.cancel.store(true, Ordering::Relaxed);
    let r = load(&split_glb(&test_scene("rod"), &dir, "rod_external"), &opts);
    assert!(matches!(r, Err(SceneError::Cancelled(_))), "{:?}", r.err());
    let _ = std::fs::remove_dir_all(dir);
}

/// Triangles of a scene in world space, each as 9 coordinates, sorted.
fn world_triangles(s: &hrtao_scene::Scene) -> Vec<[u32; 9]> {
    let mut out = Vec::new();
    for inst in &s.instances {
        for p in &s.meshes[inst.mesh as usize].primitives {
            for t in p.indices.chunks_exact(3) {
                let mut tri = [0u32; 9];
                for (k, &i) in t.iter().enumerate() {
                    let w = inst
                        .transform
                        .transform_point3(glam::Vec3::from(p.positions[i as usize]));
                    for (c, v) in w.to_array().into_iter().enumerate() {
                        tri[k * 3 + c] = v.to_bits();
                    }
                }
                out.push(tri);
            }
        }
    }
    out.sort();
    out
}

/// The same model as STL (binary, binary with a `solid` header, ASCII), PLY (ASCII, binary) and glTF: same
/// triangles and bounds; counts far beyond the file's size are refused before reading.
#[test]
fn stl_and_gltf_of_the_same_model_agree() {
    let dir = temp_dir("stl");
    let cases = write_corpus(&dir).unwrap();
    let get = |name: &str| load_case(&cases, name).unwrap();
    let gltf = get("valid_reference");
    for name in [
        "stl_binary",
        "stl_binary_header_says_solid",
        "stl_ascii",
        "ply_ascii",
        "ply_binary",
    ] {
        let stl = get(name);
        assert_eq!(stl.meshes.len(), 1);
        assert_eq!(stl.instances.len(), 1);
        assert_eq!(world_triangles(&stl), world_triangles(&gltf), "{name}");
        assert_eq!(stl.bounds().min, gltf.bounds().min);
        assert_eq!(stl.bounds().max, gltf.bounds().max);
    }
    let c = cases
        .iter()
        .find(|c| c.name == "stl_count_far_beyond_file_size")
        .unwrap();
    let e = load(&c.path, &LoadOptions::default()).unwrap_err().to_string();
    assert!(
        e.contains("4000000000 triangles") && e.contains("stl_count_far"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
