//! The frame's barriers follow from the passes' declared accesses: every hazard between two recorded commands
//! has a barrier between them (with the stages of both sides), and passes that touch different buffers share
//! one, so a frame records fewer barriers than dispatches. On the bundled scene at 160 x 90: a young frame (an
//! empty map), a navigation frame (a moving camera over a settled map), both primary visibilities.
mod common;

use common::*;

use hrtao_core::barrier::{uncovered_hazards, Event};
use hrtao_core::{AoSettings, Primary};

const R: f32 = 8.0;

/// (dispatches, barriers) of a recorded frame.
fn counts(events: &[Event]) -> (usize, usize) {
    let dispatches = events
        .iter()
        .filter(|e| matches!(e, Event::Command { pass: Some(_), .. }))
        .count();
    let barriers = events.iter().filter(|e| matches!(e, Event::Barrier(_))).count();
    (dispatches, barriers)
}

fn sequence(events: &[Event]) -> String {
    events
        .iter()
        .map(|e| match e {
            Event::Barrier(_) => "|".to_string(),
            Event::Command { label, indirect, .. } => format!("{label}{}", if *indirect { "*" } else { "" }),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Records a young frame and a navigation frame with `primary` and checks both; returns their counts.
fn young_and_navigation(settings: AoSettings, primary: Primary) -> [(usize, usize); 2] {
    let (gpu, scene, cam, sg) = on_gpu(bundled(160, 90));
    let mut r = Headless::new(&gpu, cam.width, cam.height, settings).unwrap();
    r.set_primary(primary);
    let mut out = Vec::new();
    let young = r.render(&sg, scene.f(), &cam).unwrap();
    assert!(young.ray_pixels > 0, "the first frame queues pixels for rays");
    let frames = [r.last_frame_events().to_vec()];
    // Settle the map, then move: a navigation frame.
    for _ in 0..24 {
        r.render(&sg, scene.f(), &cam).unwrap();
    }
    for i in 1..=4 {
        let mut moved = cam;
        moved.eye[0] += 0.25 * i as f32;
        r.render(&sg, scene.f(), &moved).unwrap();
    }
    let frames = [frames[0].clone(), r.last_frame_events().to_vec()];
    for (name, events) in ["young", "moving (after 24 still frames)"].iter().zip(&frames) {
        let problems = uncovered_hazards(events);
        assert!(
            problems.is_empty(),
            "{name} frame ({primary:?}): {}\n{}",
            sequence(events),
            problems.join("\n")
        );
        let (dispatches, barriers) = counts(events);
        println!(
            "{name} frame ({primary:?}): {dispatches} dispatches, {barriers} barriers: {}",
            sequence(events)
        );
        out.push((dispatches, barriers));
    }
    assert_clean(&gpu);
    [out[0], out[1]]
}

fn defaults() -> AoSettings {
    let mut s = AoSettings::default().with_radius(R);
    s.map.hash_capacity = 1 << 17;
    s
}

#[test]
fn every_hazard_has_a_barrier_and_independent_passes_share_one() {
    // With our additions, contact_detail.comp (its obscurance) shares the cell finder's barrier and the
    // statistics copy composite's: fewer barriers than dispatches, the end-of-frame one included (a full barrier
    // followed every dispatch before, and the host-read barrier the frame).
    for (dispatches, barriers) in young_and_navigation(defaults(), Primary::RayQuery) {
        assert!(
            barriers < dispatches,
            "{barriers} barriers for {dispatches} dispatches"
        );
    }
    // The paper's passes each read what the one before wrote: one barrier after each, the last one ending the
    // frame (the statistics copy shares composite's).
    for (dispatches, barriers) in young_and_navigation(defaults().paper(), Primary::RayQuery) {
        assert!(
            barriers <= dispatches,
            "{barriers} barriers for {dispatches} dispatches"
        );
    }
}

#[test]
fn raster_visibility_hands_off_to_compute_behind_a_barrier() {
    let [young, navigation] = young_and_navigation(defaults(), Primary::Raster);
    for (dispatches, barriers) in [young, navigation] {
        // The draws and their copy are commands besides the dispatches, behind a barrier of their own.
        assert!(
            barriers <= dispatches,
            "{barriers} barriers for {dispatches} dispatches"
        );
    }
}

/// The checker catches a missing barrier: with each barrier of a young frame removed in turn, except the ones
/// before the frame's first command and after its last, it reports a hazard.
#[test]
fn checker_reports_a_removed_barrier() {
    let (gpu, scene, cam, sg) = on_gpu(bundled(160, 90));
    let mut r = Headless::new(&gpu, cam.width, cam.height, defaults()).unwrap();
    r.render(&sg, scene.f(), &cam).unwrap();
    let events = r.last_frame_events().to_vec();
    let last = events.len() - 1;
    let mut checked = 0;
    for (i, e) in events.iter().enumerate() {
        if matches!(e, Event::Barrier(_)) && i > 0 && i < last {
            let mut mutated = events.clone();
            mutated.remove(i);
            let problems = uncovered_hazards(&mutated);
            assert!(
                !problems.is_empty(),
                "barrier {i} of {} is not needed",
                sequence(&events)
            );
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked} barriers checked");
    assert_clean(&gpu);
}
