//! The bridge against models OCCT writes itself: structure, instancing, colours, visibility, units.

use hrtao_occt::{read, write_test_model, Format, Model, Tessellation, TestModel};

fn roundtrip(name: &str, format: Format, model: TestModel) -> Model {
    let dir = std::env::temp_dir().join(format!("hrtao-occt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    write_test_model(&p, format, model).unwrap();
    let m = read(&p, format, &Tessellation::default(), &mut |_, _| false).unwrap();
    let _ = std::fs::remove_file(p);
    m
}

/// Triangles of every placed occurrence.
fn placed_triangles(m: &Model) -> usize {
    m.nodes
        .iter()
        .filter_map(|n| n.part)
        .map(|p| {
            m.parts[p as usize]
                .primitives
                .iter()
                .map(|q| q.indices.len() / 3)
                .sum::<usize>()
        })
        .sum()
}

#[test]
fn step_bolt_pattern_shares_one_bolt_mesh() {
    let m = roundtrip("bolts.step", Format::Step, TestModel::BoltPattern(8));
    let placed: Vec<_> = m.nodes.iter().filter_map(|n| n.part).collect();
    assert_eq!(placed.len(), 9, "plate + 8 bolts");
    assert_eq!(m.parts.len(), 2, "one plate, one bolt");
    let bolt = m.parts.iter().position(|p| p.name == "bolt").unwrap() as u32;
    assert_eq!(placed.iter().filter(|&&p| p == bolt).count(), 8);
    assert_eq!(m.nodes[0].name, "bolt_pattern");
    assert_eq!(m.nodes[0].part, None);
    assert_eq!(m.file_unit_m, Some(1e-3));
    assert_eq!(m.model_unit_m, 1e-3);
    // Bolt k sits at 40 mm from the axis, at angle 2 pi k / 8.
    let xs: Vec<[f64; 2]> = m
        .nodes
        .iter()
        .filter(|n| n.part == Some(bolt))
        .map(|n| [n.world[12], n.world[13]])
        .collect();
    for (k, [x, y]) in xs.iter().enumerate() {
        let a = std::f64::consts::TAU * k as f64 / 8.0;
        assert!(
            (x - 40.0 * a.cos()).abs() < 1e-9 && (y - 40.0 * a.sin()).abs() < 1e-9,
            "{k}: {x} {y}"
        );
    }
}

/// IGES has no product structure like STEP's: the same geometry comes back, flattened.
#[test]
fn iges_bolt_pattern_has_the_same_geometry() {
    let step = roundtrip("bolts2.step", Format::Step, TestModel::BoltPattern(8));
    let iges = roundtrip("bolts2.igs", Format::Iges, TestModel::BoltPattern(8));
    let (s, i) = (placed_triangles(&step), placed_triangles(&iges));
    assert!(
        s > 0 && (i as f64 / s as f64 - 1.0).abs() < 0.2,
        "STEP {s} vs IGES {i} triangles"
    );
    assert_eq!(iges.file_unit_m, Some(1e-3));
}

#[test]
fn colours_and_hidden_occurrences() {
    let m = roundtrip("coloured.step", Format::Step, TestModel::Coloured);
    let red = m.parts.iter().find(|p| p.name == "red_part").unwrap();
    assert_eq!(red.primitives.len(), 1);
    let c = red.primitives[0].color.unwrap();
    assert!(c[0] > 0.99 && c[1] < 0.01 && c[2] < 0.01, "{c:?}");
    assert!(!red.primitives[0].face_color);
    let faced = m.parts.iter().find(|p| p.name == "blue_top_part").unwrap();
    assert_eq!(faced.primitives.len(), 2, "the blue face and the rest");
    let blue = faced.primitives.iter().find(|p| p.face_color).unwrap();
    assert_eq!(blue.indices.len() / 3, 2, "one square face");
    let green = m.nodes.iter().find(|n| n.name == "green_occurrence").unwrap();
    let g = green.color.unwrap();
    assert!(g[1] > 0.99 && g[0] < 0.01, "{g:?}");
    let hidden = m.nodes.iter().find(|n| n.name == "hidden_occurrence").unwrap();
    assert!(!hidden.visible);
    assert_eq!(
        m.nodes.iter().filter(|n| n.part.is_some() && n.visible).count(),
        3
    );
}

#[test]
fn a_user_break_stops_the_kernel() {
    let dir = std::env::temp_dir().join(format!("hrtao-occt-break-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("many.step");
    write_test_model(&p, Format::Step, TestModel::ManySolids(50)).unwrap();
    let mut calls = 0;
    let e = read(&p, Format::Step, &Tessellation::default(), &mut |_, _| {
        calls += 1;
        true
    })
    .unwrap_err();
    assert!(matches!(e, hrtao_occt::Error::Stopped), "{e}");
    assert!(calls >= 1);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn garbage_is_an_error_not_a_crash() {
    let dir = std::env::temp_dir().join(format!("hrtao-occt-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("garbage.step");
    std::fs::write(&p, b"\x00\x01 not a step file at all").unwrap();
    let e = read(&p, Format::Step, &Tessellation::default(), &mut |_, _| false).unwrap_err();
    assert!(e.to_string().contains("STEP"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Reads and writes on several threads at once (OCCT's data exchange keeps process-wide state): each thread gets
/// the same model back as a read on one thread. Without the kernel lock in `read`/`write_test_model` the test
/// binary aborts inside OCCT (SIGABRT, 4 runs of 4; the suite's other tests met it as a SIGSEGV).
#[test]
fn concurrent_reads_and_writes_each_get_their_own_model() {
    let case = |t: u32, round: u32| {
        let format = if (t + round).is_multiple_of(2) {
            Format::Step
        } else {
            Format::Iges
        };
        (format, 2 + t)
    };
    let ext = |f: Format| if f == Format::Step { "step" } else { "igs" };
    // What one thread reads, per case: (occurrences placed, their triangles).
    let seen = |m: &Model| {
        (
            m.nodes.iter().filter(|n| n.part.is_some()).count(),
            placed_triangles(m),
        )
    };
    let expected: std::collections::HashMap<(bool, u32), (usize, usize)> = (0..4u32)
        .flat_map(|t| (0..3).map(move |r| case(t, r)))
        .map(|(f, n)| {
            let m = roundtrip(&format!("seq-{n}.{}", ext(f)), f, TestModel::BoltPattern(n));
            ((f == Format::Step, n), seen(&m))
        })
        .collect();
    let expected = std::sync::Arc::new(expected);
    let threads: Vec<_> = (0..4u32)
        .map(|t| {
            let expected = expected.clone();
            std::thread::spawn(move || {
                for round in 0..3 {
                    let (f, n) = case(t, round);
                    let m = roundtrip(
                        &format!("race-{t}-{round}.{}", ext(f)),
                        f,
                        TestModel::BoltPattern(n),
                    );
                    assert_eq!(
                        seen(&m),
                        expected[&(f == Format::Step, n)],
                        "thread {t} round {round} ({})",
                        ext(f)
                    );
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
}
