//! The bridge against models OCCT writes itself: structure, instancing, colours, visibility, units.

use hrtao_occt::{
    read, write_test_model, write_test_model_subfigures, Format, Model, Tessellation, TestModel,
};

fn roundtrip(name: &str, format: Format, model: TestModel) -> Model {
    roundtrip_with(name, format, |p| write_test_model(p, format, model))
}

/// Written as IGES with subfigures (308 definitions, 408 instances) and read back.
fn roundtrip_subfigures(name: &str, model: TestModel) -> Model {
    roundtrip_with(name, Format::Iges, |p| write_test_model_subfigures(p, model))
}

fn roundtrip_with(
    name: &str,
    format: Format,
    write: impl FnOnce(&std::path::Path) -> Result<(), hrtao_occt::Error>,
) -> Model {
    let dir = std::env::temp_dir().join(format!("hrtao-occt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    write(&p).unwrap();
    let m = read(&p, format, &Tessellation::default(), &mut |_, _| false).unwrap();
    let _ = std::fs::remove_file(p);
    m
}

/// Corners of the box around every placed occurrence's vertices, in file coordinates.
fn placed_bounds(m: &Model) -> [[f64; 3]; 2] {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for n in &m.nodes {
        let Some(part) = n.part else { continue };
        let w = &n.world;
        for q in &m.parts[part as usize].primitives {
            for p in &q.positions {
                for r in 0..3 {
                    let v = w[r] * p[0] as f64 + w[4 + r] * p[1] as f64 + w[8 + r] * p[2] as f64 + w[12 + r];
                    lo[r] = lo[r].min(v);
                    hi[r] = hi[r].max(v);
                }
            }
        }
    }
    [lo, hi]
}

/// The same placed geometry: triangles within 20 % (IGES turns some surfaces into others, meshed a little
/// differently) and the same bounds.
fn assert_same_geometry(a: &Model, b: &Model, what: &str) {
    let (ta, tb) = (placed_triangles(a), placed_triangles(b));
    assert!(
        ta > 0 && (tb as f64 / ta as f64 - 1.0).abs() < 0.2,
        "{what}: {ta} vs {tb} triangles"
    );
    let (ba, bb) = (placed_bounds(a), placed_bounds(b));
    for k in 0..2 {
        for r in 0..3 {
            assert!(
                (ba[k][r] - bb[k][r]).abs() < 1e-3,
                "{what}: bounds {ba:?} vs {bb:?}"
            );
        }
    }
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

/// `TestModel::BoltPattern(8)` as written: one assembly of a plate and one bolt mesh placed 8 times, named.
fn check_bolt_pattern(m: &Model) {
    let placed: Vec<_> = m.nodes.iter().filter_map(|n| n.part).collect();
    assert_eq!(placed.len(), 9, "plate + 8 bolts");
    assert_eq!(m.parts.len(), 2, "one plate, one bolt");
    let tree: Vec<_> = m.nodes.iter().map(|n| (n.name.as_str(), n.parent)).collect();
    assert_eq!(m.nodes.len(), 10, "the assembly, the plate, 8 bolts: {tree:?}");
    assert!(m.nodes[1..].iter().all(|n| n.parent == Some(0)), "{tree:?}");
    assert_eq!(m.nodes[0].name, "bolt_pattern");
    assert_eq!(m.nodes[0].part, None);
    let names: Vec<_> = m.parts.iter().map(|p| p.name.as_str()).collect();
    let bolt = names
        .iter()
        .position(|&p| p == "bolt")
        .unwrap_or_else(|| panic!("{names:?}")) as u32;
    assert!(names.contains(&"plate"), "{names:?}");
    assert_eq!(placed.iter().filter(|&&p| p == bolt).count(), 8);
    assert_eq!(m.file_unit_m, Some(1e-3));
    assert_eq!(m.model_unit_m, 1e-3);
    // Bolt k sits at 40 mm from the axis, at angle 2 pi k / 8.
    let bolts: Vec<_> = m.nodes.iter().filter(|n| n.part == Some(bolt)).collect();
    for (k, n) in bolts.iter().enumerate() {
        let [x, y] = [n.world[12], n.world[13]];
        let a = std::f64::consts::TAU * k as f64 / 8.0;
        assert!(
            (x - 40.0 * a.cos()).abs() < 1e-9 && (y - 40.0 * a.sin()).abs() < 1e-9,
            "{k}: {x} {y}"
        );
        assert_eq!(n.name, format!("bolt{}", k + 1));
    }
}

#[test]
fn step_bolt_pattern_shares_one_bolt_mesh() {
    check_bolt_pattern(&roundtrip("bolts.step", Format::Step, TestModel::BoltPattern(8)));
}

/// IGES states that one part is placed several times with subfigures: the bolt is one definition (308) placed by
/// 8 instances (408), the plate written inline beside them in the pattern's definition. It reads back as STEP does.
#[test]
fn iges_subfigure_bolt_pattern_shares_one_bolt_mesh() {
    let iges = roundtrip_subfigures("bolts-sub.igs", TestModel::BoltPattern(8));
    check_bolt_pattern(&iges);
    let step = roundtrip("bolts-sub.step", Format::Step, TestModel::BoltPattern(8));
    assert_same_geometry(&step, &iges, "STEP vs IGES subfigures");
}

/// A definition placed twice (the bolt pattern, its plate inline beside the bolts' instances) is one
/// sub-assembly: its plate is meshed once, as in STEP.
#[test]
fn iges_subfigure_placed_twice_is_one_definition() {
    let step = roundtrip("pair.step", Format::Step, TestModel::BoltPatternPair(4));
    let iges = roundtrip_subfigures("pair.igs", TestModel::BoltPatternPair(4));
    for (m, what) in [(&step, "STEP"), (&iges, "IGES")] {
        let names: Vec<_> = m.parts.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names.len(), 2, "{what}: one plate, one bolt: {names:?}");
        let plate = names.iter().position(|&n| n == "plate").unwrap() as u32;
        let plates: Vec<_> = m.nodes.iter().filter(|n| n.part == Some(plate)).collect();
        let xs: Vec<f64> = plates.iter().map(|n| n.world[12]).collect();
        assert_eq!(xs, [0.0, 200.0], "{what}");
        assert_eq!(m.nodes.iter().filter(|n| n.part.is_some()).count(), 10, "{what}");
        assert_eq!(
            m.nodes.iter().filter(|n| n.parent.is_none()).count(),
            1,
            "{what}: one root"
        );
        let sides: Vec<_> = m
            .nodes
            .iter()
            .filter(|n| n.parent == Some(0))
            .map(|n| (n.name.as_str(), n.part))
            .collect();
        assert_eq!(sides, [("left", None), ("right", None)], "{what}");
        assert_eq!(m.nodes[0].name, "two_patterns", "{what}");
    }
    assert_same_geometry(&step, &iges, "STEP vs IGES subfigures");
}

/// OCCT's IGES writer writes no subfigures: every bolt is a copy of the bolt's geometry, so nothing is shared and
/// the pattern comes back as one part. The same geometry comes back.
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

/// `TestModel::Coloured` as written: a part's, a face's and an occurrence's colour; a hidden occurrence.
fn check_coloured(m: &Model) {
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
fn colours_and_hidden_occurrences() {
    check_coloured(&roundtrip("coloured.step", Format::Step, TestModel::Coloured));
}

/// In IGES: the part's colour on its definition (308), the face's on the face entity, the occurrence's on its
/// instance (408), the hidden occurrence a blanked instance.
#[test]
fn iges_subfigure_colours_and_hidden_occurrences() {
    check_coloured(&roundtrip_subfigures("coloured.igs", TestModel::Coloured));
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

/// A STEP cylinder placed twice: one part, its side normals radial and its caps' axial and outward; the upside-down
/// occurrence is the same part under a 180° turn (normals are the part's; the placement turns them).
#[test]
fn cylinder_normals_are_radial_on_the_side_and_axial_on_the_caps() {
    let m = roundtrip("cylinder.step", Format::Step, TestModel::Cylinder);
    assert_eq!(
        m.parts.len(),
        1,
        "{:?}",
        m.parts.iter().map(|p| &p.name).collect::<Vec<_>>()
    );
    assert_eq!(m.nodes.iter().filter(|n| n.part == Some(0)).count(), 2);
    let (mut side, mut cap) = (0, 0);
    for q in &m.parts[0].primitives {
        let (s, c) = hrtao_occt::testing::check_cylinder_normals(&q.positions, &q.normals, &q.indices);
        side += s;
        cap += c;
    }
    assert!(
        side >= 60 && cap >= 30,
        "{side} side and {cap} cap vertices checked"
    );
}
