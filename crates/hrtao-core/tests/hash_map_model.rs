//! A CPU model of `find_or_insert` (shaders/hash_map.glsl), line for line, checked under every interleaving
//! of its threads by `loom`. Lavapipe's two threads rarely interleave inside one probe, so the GPU tests
//! cannot provoke these races; the model can.
//!
//! The model uses the shader's memory orderings: GLSL's `atomicLoad(..., gl_SemanticsRelaxed)` and
//! `atomicCompSwap`/`atomicExchange` without semantics are relaxed, so every atomic here is `Relaxed`. A cell
//! is its stamp and its ray counter (`HashCell::samples`, standing for all counters `reset_counters` empties).
//!
//! Properties checked after all threads finish:
//! - every thread that asked for key K got the one slot holding K (no duplicate keys, no lost inserts), or,
//!   when the key's probe run is exhausted (max_probe live cells of other keys), no slot and no change;
//! - a cell claimed or re-stamped in this frame is never taken over by another key in the same frame;
//! - a key that lives further down its probe run is found, not re-inserted at a stale slot before it;
//! - a claimed cell's counters are empty (`reset_counters`), a found one keeps its rays;
//! - probe runs wrap at the end of the table.
use loom::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};
use loom::sync::Arc;

const EMPTY: u32 = 0;
const INVALID: u32 = u32::MAX;
const ATTEMPTS: u32 = 4;

/// One frame's view of the map (FrameGlobals fields the probe reads).
#[derive(Clone, Copy)]
struct Frame {
    frame_index: u32,
    f_start_frame: u32,
    stale_frames: u32,
    max_probe: u32,
}

fn stamp(checksum: u32, frame: u32) -> u64 {
    checksum as u64 | (frame as u64) << 32
}
fn checksum(s: u64) -> u32 {
    s as u32
}
fn frame(s: u64) -> u32 {
    (s >> 32) as u32
}

fn reclaimable(f: &Frame, s: u64) -> bool {
    let age = f.frame_index.wrapping_sub(frame(s));
    age > f.frame_index.wrapping_sub(f.f_start_frame) || age > f.stale_frames
}

fn cas(a: &AtomicU64, expected: u64, new: u64) -> u64 {
    match a.compare_exchange(expected, new, Relaxed, Relaxed) {
        Ok(v) | Err(v) => v,
    }
}

/// One slot of the map: `HashCell::stamp` and `HashCell::samples`.
struct Cell {
    stamp: AtomicU64,
    samples: AtomicU32,
}

/// Mirror of hash_map.glsl `reset_counters`.
fn reset_counters(cell: &Cell) {
    cell.samples.swap(0, Relaxed);
}

/// Mirror of hash_map.glsl `find_or_insert`.
fn find_or_insert(cells: &[Cell], f: &Frame, home: u32, key: u32) -> u32 {
    let mask = cells.len() as u32 - 1;
    let mine = stamp(key, f.frame_index);
    for _ in 0..ATTEMPTS {
        let mut candidate = INVALID;
        let mut expected = 0u64;
        let mut lost = false;
        for i in 0..f.max_probe {
            let slot = (home + i) & mask;
            let mut s = cells[slot as usize].stamp.load(Relaxed);
            let c = checksum(s);
            if c == key {
                while frame(s) != f.frame_index {
                    let prev = cas(&cells[slot as usize].stamp, s, mine);
                    if prev == s {
                        break;
                    }
                    s = prev;
                }
                if checksum(s) == key {
                    return slot;
                }
                lost = true;
                break;
            }
            if c == EMPTY {
                if candidate == INVALID {
                    candidate = slot;
                    expected = s;
                }
                break;
            }
            if candidate == INVALID && reclaimable(f, s) {
                candidate = slot;
                expected = s;
            }
        }
        if lost {
            continue;
        }
        if candidate == INVALID {
            break;
        }
        let prev = cas(&cells[candidate as usize].stamp, expected, mine);
        if prev == expected {
            reset_counters(&cells[candidate as usize]);
            return candidate;
        }
        if checksum(prev) == key {
            return candidate;
        }
    }
    INVALID
}

const FRAME: Frame = Frame {
    frame_index: 100,
    f_start_frame: 50,
    stale_frames: 10,
    max_probe: 4,
};
/// A stamp of a cell last used long ago (reclaimable), and of one used last frame (live).
const STALE: u32 = 80;
const LIVE: u32 = 99;

/// Rays an occupied cell holds at the start (its key's, from earlier frames).
const OLD_RAYS: u32 = 7;

fn table(init: &[u64]) -> Arc<Vec<Cell>> {
    Arc::new(
        init.iter()
            .map(|&s| Cell {
                stamp: AtomicU64::new(s),
                samples: AtomicU32::new(if checksum(s) == EMPTY { 0 } else { OLD_RAYS }),
            })
            .collect(),
    )
}

fn snapshot(cells: &[Cell]) -> Vec<u64> {
    cells.iter().map(|c| c.stamp.load(Relaxed)).collect()
}

fn samples(cells: &[Cell]) -> Vec<u32> {
    cells.iter().map(|c| c.samples.load(Relaxed)).collect()
}

/// Whether the probe run of `home` (max_probe slots, wrapping) holds only live cells of keys other than `key`
/// in `cells`: an insert of `key` may then fail.
fn exhausted(cells: &[u64], home: u32, key: u32) -> bool {
    let mask = cells.len() as u32 - 1;
    (0..FRAME.max_probe).all(|i| {
        let s = cells[((home + i) & mask) as usize];
        checksum(s) != EMPTY && checksum(s) != key && !reclaimable(&FRAME, s)
    })
}

/// Checks the properties over the final table: each key held at most once; every returned slot holds the key
/// its thread asked for, stamped this frame; a thread without a slot met an exhausted run; a cell whose key
/// changed holds no rays of the old key, and one that kept its key keeps its rays.
fn check(init: &[u64], cells: &[u64], rays: &[u32], asked: &[(u32, u32, u32)]) {
    for (slot, (&before, &after)) in init.iter().zip(cells).enumerate() {
        let expected = if checksum(before) == checksum(after) {
            if checksum(before) == EMPTY {
                0
            } else {
                OLD_RAYS
            }
        } else {
            0
        };
        assert_eq!(
            rays[slot], expected,
            "slot {slot}: {before:x} -> {after:x} holds {} rays",
            rays[slot]
        );
    }
    for &(home, key, slot) in asked {
        if slot == INVALID {
            assert!(
                exhausted(cells, home, key),
                "key {key} was not inserted although the run has room: {cells:x?}"
            );
            continue;
        }
        let mask = cells.len() as u32 - 1;
        assert!(
            slot.wrapping_sub(home) & mask < FRAME.max_probe,
            "key {key} (home {home}) in slot {slot}, past its probe run of {}",
            FRAME.max_probe
        );
        let (key, slot) = (&key, &slot);
        assert_eq!(
            checksum(cells[*slot as usize]),
            *key,
            "slot {slot} lost key {key}: {cells:x?}"
        );
        assert_eq!(frame(cells[*slot as usize]), FRAME.frame_index);
        let copies = cells.iter().filter(|s| checksum(**s) == *key).count();
        assert_eq!(copies, 1, "key {key} held {copies} times: {cells:x?}");
    }
}

fn run_threads(init: &[u64], requests: &[(u32, u32)]) {
    let requests = requests.to_vec();
    let init = init.to_vec();
    let start = init.clone();
    let mut model = loom::model::Builder::new();
    // Bounded preemptions keep three-thread runs to seconds; races need at most a couple of preemptions.
    model.preemption_bound = Some(3);
    model.check(move || {
        let cells = table(&init);
        let handles: Vec<_> = requests
            .iter()
            .map(|&(home, key)| {
                let cells = cells.clone();
                loom::thread::spawn(move || (home, key, find_or_insert(&cells, &FRAME, home, key)))
            })
            .collect();
        let asked: Vec<(u32, u32, u32)> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        check(&start, &snapshot(&cells), &samples(&cells), &asked);
    });
}

#[test]
fn a_key_further_down_the_run_is_found_not_duplicated() {
    // Slot 0 is stale (another key), key 7 lives at slot 2: the probe must return 2.
    let init = [stamp(3, STALE), stamp(4, LIVE), stamp(7, LIVE), 0, 0, 0, 0, 0];
    run_threads(&init, &[(0, 7)]);
    // And with a second thread inserting another key at the same home at the same time.
    run_threads(&init, &[(0, 7), (0, 9)]);
}

#[test]
fn two_threads_inserting_one_key_share_its_cell() {
    // The home slot is reclaimable: both threads aim at it, one wins, the other must use the winner's cell.
    run_threads(&[stamp(3, STALE), 0, 0, 0, 0, 0, 0, 0], &[(0, 5), (0, 5)]);
    // The home slot is free.
    run_threads(&[0; 8], &[(0, 5), (0, 5)]);
}

#[test]
fn a_cell_claimed_this_frame_is_not_stolen() {
    // Key 5 and key 6 both want the one stale slot 0; key 5 is also asked twice. Whoever claims slot 0 keeps
    // it: the other key lands in slot 1, and the final table holds each key once.
    run_threads(&[stamp(3, STALE), 0, 0, 0, 0, 0, 0, 0], &[(0, 5), (0, 6), (0, 5)]);
}

#[test]
fn a_stale_cell_of_the_key_is_kept_or_cleanly_taken_over() {
    // Key 5 sits stale in its home slot; key 6 (same home) may reclaim it concurrently. Either key 5 keeps its
    // cell (re-stamped) and key 6 goes to slot 1, or key 6 takes slot 0 and key 5 is re-inserted once.
    run_threads(&[stamp(5, STALE), 0, 0, 0, 0, 0, 0, 0], &[(0, 5), (0, 6)]);
}

#[test]
fn cells_of_an_old_f_are_reclaimed_at_once() {
    // Last used at frame 49, before the current F's first frame 50, or at frame 60, 40 frames ago (more than
    // stale_frames): reclaimable. Used at frame 95 of the current F: live.
    let f = FRAME;
    assert!(reclaimable(&f, stamp(1, 49)));
    assert!(!reclaimable(&f, stamp(1, 95)));
    assert!(reclaimable(&f, stamp(1, 60)));
    // Wrapping frame numbers.
    let w = Frame {
        frame_index: 5,
        f_start_frame: u32::MAX - 10,
        ..f
    };
    assert!(!reclaimable(&w, stamp(1, u32::MAX - 2)));
    assert!(reclaimable(&w, stamp(1, u32::MAX - 20)));
}

#[test]
fn a_full_run_fails_cleanly() {
    // Every slot of the probe window is live with other keys: no insert, no slot changed.
    let init = [
        stamp(1, LIVE),
        stamp(2, LIVE),
        stamp(3, LIVE),
        stamp(4, LIVE),
        0,
        0,
        0,
        0,
    ];
    loom::model(move || {
        let cells = table(&init);
        assert_eq!(find_or_insert(&cells, &FRAME, 0, 9), INVALID);
        assert_eq!(snapshot(&cells), init.to_vec());
    });
}

/// Probe runs wrap at the end of the table: homes 6 and 7 of 8 slots probe 6, 7, 0, 1. Key 5 lives at slot 0
/// (after the wrap) and is found there; key 9 takes the stale slot 1 (its counters emptied). Catches a probe
/// that does not wrap (`home + i` without the mask: out of the table) and one that wraps with a wrong mask.
#[test]
fn probe_runs_wrap_at_the_end_of_the_table() {
    let init = [
        stamp(5, LIVE),
        stamp(3, STALE),
        0,
        0,
        0,
        0,
        stamp(1, LIVE),
        stamp(2, LIVE),
    ];
    run_threads(&init, &[(6, 5), (7, 9)]);
    run_threads(&init, &[(7, 9), (6, 9)]);
}

/// Probe exhaustion: the run of home 6 (6, 7, 0, 1, wrapping) has one free slot left. Two keys race for it:
/// one gets it, the other fails cleanly (no slot, no cell changed), never a fifth slot past max_probe. Catches a
/// probe that runs past max_probe (the loser would land in slot 2) and a failed insert that changes a cell.
#[test]
fn an_exhausted_probe_run_fails_cleanly_under_contention() {
    let init = [stamp(1, LIVE), 0, 0, 0, 0, 0, stamp(2, LIVE), stamp(3, LIVE)];
    run_threads(&init, &[(6, 8), (6, 9)]);
}

/// `reset_counters`: a cell claimed for a new key (a stale one, or one of an old F) starts with no rays, and a
/// cell found under its own key keeps them, also while another thread claims a neighbour. Catches a claim
/// without the reset (the old key's rays would count for the new key) and a reset on a found cell (its rays
/// would be lost).
#[test]
fn a_claimed_cell_starts_empty_and_a_found_one_keeps_its_rays() {
    let init = [stamp(5, LIVE), stamp(3, STALE), stamp(4, 40), 0, 0, 0, 0, 0];
    run_threads(&init, &[(0, 5), (0, 6), (1, 7)]);
}
