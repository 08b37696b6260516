//! Randomized robustness (the suite's stand-in for the cargo-fuzz targets in fuzz/, which need nightly):
//! mutated glTF/GLB/OBJ files must load or fail with an error, never panic, hang or abort.
mod common;

use common::{split_glb, test_scene};
use proptest::prelude::*;
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hrtao-prop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[derive(Clone, Debug)]
enum Mutation {
    Flip(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Overwrite(usize, u32),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Flip(i, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, v)| Mutation::Insert(i, v)),
        (any::<usize>(), any::<u32>()).prop_map(|(i, v)| Mutation::Overwrite(i, v)),
    ]
}

fn apply(mut data: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        if data.is_empty() {
            break;
        }
        let n = data.len();
        match m {
            Mutation::Flip(i, b) => data[i % n] ^= b | 1,
            Mutation::Truncate(i) => data.truncate(i % n),
            Mutation::Insert(i, v) => {
                let at = i % n;
                data.splice(at..at, v.iter().cloned());
            }
            Mutation::Overwrite(i, v) => {
                let at = i % n;
                for (k, b) in v.to_le_bytes().iter().enumerate() {
                    if at + k < n {
                        data[at + k] = *b;
                    }
                }
            }
        }
    }
    data
}

fn check(name: &str, bytes: &[u8]) {
    let path = scratch(name);
    std::fs::write(&path, bytes).unwrap();
    // Ok or Err are both fine; a panic fails the property.
    let _ = hrtao_scene::load(path.to_str().unwrap(), &mut |_| {});
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_glb_never_panics(muts in proptest::collection::vec(mutation(), 1..6)) {
        let rod = std::fs::read(test_scene("rod")).unwrap();
        check("m.glb", &apply(rod, &muts));
    }

    #[test]
    fn mutated_gltf_json_never_panics(muts in proptest::collection::vec(mutation(), 1..6)) {
        // The JSON part of a small real file: the rod as .gltf with its buffer in rod_external.bin beside it.
        let dir = scratch("x").parent().unwrap().to_path_buf();
        let json = std::fs::read(split_glb(&test_scene("rod"), &dir, "rod_external")).unwrap();
        check("m.gltf", &apply(json, &muts));
    }

    #[test]
    fn random_obj_text_never_panics(lines in proptest::collection::vec(
        prop_oneof![
            (any::<f32>(), any::<f32>(), any::<f32>()).prop_map(|(a, b, c)| format!("v {a} {b} {c}")),
            (any::<i32>(), any::<i32>(), any::<i32>()).prop_map(|(a, b, c)| format!("f {a} {b} {c}")),
            (-20i32..20, -20i32..20, -20i32..20).prop_map(|(a, b, c)| format!("f {a} {b} {c}")),
            "[a-z]{0,3} [0-9./-]{0,12}".prop_map(|s| s),
        ], 0..40)) {
        check("m.obj", lines.join("\n").as_bytes());
    }
}
