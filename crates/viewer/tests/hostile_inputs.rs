//! Every file of the hostile corpus through `hrtao render`: a clear error naming the file (exit 1) or a correct
//! image (exit 0, finite AO), never a panic, a hang or an abort.
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use hrtao_scene::hostile::{write_corpus, Expect};

#[test]
fn hostile_files_give_errors_or_images() {
    let dir = std::env::temp_dir().join(format!("hrtao-hostile-{}", std::process::id()));
    let cases = write_corpus(&dir).unwrap();
    assert!(cases.len() >= 30, "corpus of {} files", cases.len());
    let (mut errors, mut images) = (0, 0);
    for case in &cases {
        // The loader alone agrees with the expectation.
        let loaded = hrtao_scene::load(case.path.to_str().unwrap(), &mut |_| {});
        assert_eq!(
            loaded.is_ok(),
            case.expect == Expect::Image,
            "{}: loader gave {:?}",
            case.name,
            loaded.err()
        );

        let ao = dir.join(format!("{}.pfm", case.name));
        let mut child = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args([
                "render",
                "--scene",
                case.path.to_str().unwrap(),
                "--width",
                "48",
                "--height",
                "27",
                "--rays",
                "2",
            ])
            .args(["--ao-out", ao.to_str().unwrap()])
            .env("HRTAO_VALIDATION", "1")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let start = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            if start.elapsed() > Duration::from_secs(120) {
                let _ = child.kill();
                panic!("{}: hrtao render hung", case.name);
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let mut stderr = String::new();
        std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
        assert!(!stderr.contains("panicked"), "{}: panic\n{stderr}", case.name);
        match case.expect {
            Expect::Error => {
                assert_eq!(
                    status.code(),
                    Some(1),
                    "{}: expected a clean error exit\n{stderr}",
                    case.name
                );
                let file_name = case.path.file_name().unwrap().to_str().unwrap();
                assert!(
                    stderr.contains(file_name),
                    "{}: the message names the file\n{stderr}",
                    case.name
                );
                errors += 1;
            }
            Expect::Image => {
                assert!(status.success(), "{}: expected an image\n{stderr}", case.name);
                let (_, _, data) = hrtao_core::imageio::read_pfm(&ao).unwrap();
                assert!(
                    data.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
                    "{}: AO out of range",
                    case.name
                );
                assert!(
                    !stderr.contains("validation layer reported"),
                    "{}: validation messages\n{stderr}",
                    case.name
                );
                images += 1;
            }
        }
    }
    println!(
        "{} hostile files: {errors} clear errors, {images} correct images",
        cases.len()
    );
}
