//! Fuzz target: `hrtao_scene::load` on arbitrary .obj bytes must return Ok or Err, never panic or abort.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("hrtao-fuzz-{}.obj", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = hrtao_scene::load(path.to_str().unwrap(), &mut |_| {});
    }
});
