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
//! - probe runs wrap at the end of the table;
//! - while the table has room (`FLAG_MAP_HAS_ROOM`), a stale cell is reclaimed only by a key whose probe window
//!   holds no free slot: the others take the free slot ending their run, and the stale cell keeps its AO.
//!
//! Each interleaving test runs twice: with room (free slots first) and without (stale slots first).
use hrtao_core::hash_map::FrameClock;
use loom::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};
use loom::sync::Arc;

const EMPTY: u32 = 0;
const INVALID: u32 = u32::MAX;
const ATTEMPTS: u32 = 4;

/// One frame's view of the map (FrameGlobals fields the probe reads).
#[derive(Clone, Copy, Debug)]
struct Frame {
    frame_index: u32,
    f_start_frame: u32,
    /// The cache lifetime in frames (`FrameClock::lifetime_frames`).
    lifetime_frames: u32,
    max_probe: u32,
    /// `FLAG_MAP_HAS_ROOM`.
    room: bool,
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
    age > f.frame_index.wrapping_sub(f.f_start_frame) || age > f.lifetime_frames
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
        let (mut stale, mut free) = (INVALID, INVALID);
        let (mut stale_stamp, mut free_stamp) = (0u64, 0u64);
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
                free = slot;
                free_stamp = s;
                break;
            }
            if stale == INVALID && reclaimable(f, s) {
                stale = slot;
                stale_stamp = s;
            }
        }
        if lost {
            continue;
        }
        let take_free = free != INVALID && (f.room || stale == INVALID);
        let (candidate, expected) = if take_free {
            (free, free_stamp)
        } else {
            (stale, stale_stamp)
        };
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

/// A frame of a full table (stale slots first); `ROOMY` is the same frame with room (free slots first).
const FRAME: Frame = Frame {
    frame_index: 100,
    f_start_frame: 50,
    lifetime_frames: 10,
    max_probe: 4,
    room: false,
};
const ROOMY: Frame = Frame { room: true, ..FRAME };
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
fn check(f: &Frame, init: &[u64], cells: &[u64], rays: &[u32], asked: &[(u32, u32, u32)]) {
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
        // With room, a stale cell goes to this key only when the key's window holds no free slot (free slots
        // never come back: one free at the end was free when the probe passed).
        let reclaimed = checksum(init[*slot as usize]) != EMPTY && checksum(init[*slot as usize]) != *key;
        if f.room && reclaimed {
            let window_free =
                (0..f.max_probe).any(|i| checksum(cells[((home + i) & mask) as usize]) == EMPTY);
            assert!(
                !window_free,
                "key {key} reclaimed slot {slot} although its run ends in a free slot: {cells:x?}"
            );
        }
    }
}

/// Every interleaving of one thread per request, in a full table and in one with room.
fn run_threads(init: &[u64], requests: &[(u32, u32)]) {
    for f in [FRAME, ROOMY] {
        run_threads_in(f, init, requests);
    }
}

fn run_threads_in(f: Frame, init: &[u64], requests: &[(u32, u32)]) {
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
                loom::thread::spawn(move || (home, key, find_or_insert(&cells, &f, home, key)))
            })
            .collect();
        let asked: Vec<(u32, u32, u32)> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        check(&f, &start, &snapshot(&cells), &samples(&cells), &asked);
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
    // lifetime_frames): reclaimable. Used at frame 95 of the current F: live.
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
    for f in [FRAME, ROOMY] {
        loom::model(move || {
            let cells = table(&init);
            assert_eq!(find_or_insert(&cells, &f, 0, 9), INVALID);
            assert_eq!(snapshot(&cells), init.to_vec());
        });
    }
}

/// Probe runs wrap at the end of the table: homes 6 and 7 of 8 slots probe 6, 7, 0, 1 and 7, 0, 1, 2. Key 5
/// lives at slot 0 (after the wrap) and is found there; key 9 (home 7) takes the stale slot 1 (its counters
/// emptied), or with room the free slot 2; key 8 (home 6, no free slot in its window) takes the stale slot 1
/// in both modes, racing key 9 for it without room. A key has one home (its slot and checksum come from the
/// same position, eq. 1-6): one checksum at two homes would be a checksum collision of two cells, which no rule
/// keeps apart. Catches a probe that does not wrap (`home + i` without the mask: out of the table) and one that
/// wraps with a wrong mask.
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
    run_threads(&init, &[(7, 9), (6, 8), (7, 9)]);
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

/// The slot a lone insert of `key` at `home` takes in `init` under `f`, and the table after it.
fn insert_alone(f: Frame, init: &[u64], home: u32, key: u32) -> (u32, Vec<u64>, Vec<u32>) {
    let init = init.to_vec();
    let out = std::sync::Arc::new(std::sync::Mutex::new(None));
    let seen = out.clone();
    loom::model(move || {
        let cells = table(&init);
        let slot = find_or_insert(&cells, &f, home, key);
        *seen.lock().unwrap() = Some((slot, snapshot(&cells), samples(&cells)));
    });
    let got = out.lock().unwrap().take();
    got.expect("the model ran")
}

/// Free slots before stale ones while the table has room: key 5's run (home 0) passes a stale cell of key 3 and
/// ends at the free slot 2. With room the insert takes slot 2 and key 3 keeps its cell and rays (a revisit finds
/// them); without, it recycles slot 0. Either way key 5 is then found where it went, and key 3 too when kept.
/// Catches an insert that ignores the room (`take_free = free != INVALID && stale == INVALID`, today's rule:
/// key 3's AO is lost while the table is nearly empty) and one that ignores stale slots when full (`f.room ||`
/// dropped: `take_free = free != INVALID`, the table would never recycle).
#[test]
fn with_room_an_insert_takes_the_free_slot_and_a_stale_cell_keeps_its_ao() {
    let init = [stamp(3, STALE), stamp(4, LIVE), 0, 0, 0, 0, 0, 0];
    let (slot, cells, rays) = insert_alone(ROOMY, &init, 0, 5);
    assert_eq!(slot, 2, "with room: the free slot ending the run");
    assert_eq!(
        (cells[0], rays[0]),
        (init[0], OLD_RAYS),
        "the stale cell keeps its key and rays"
    );
    assert_eq!(insert_alone(ROOMY, &cells, 0, 5).0, 2, "key 5 is found there");
    assert_eq!(
        insert_alone(ROOMY, &cells, 0, 3).0,
        0,
        "key 3 is found, stale as it was"
    );
    let (slot, cells, rays) = insert_alone(FRAME, &init, 0, 5);
    assert_eq!(slot, 0, "without room: the stale slot is recycled");
    assert_eq!((checksum(cells[0]), rays[0]), (5, 0));
    assert_eq!(insert_alone(FRAME, &cells, 0, 5).0, 0);
}

/// The cache lifetime in seconds at 10 and at 144 simulated frames per second (`FrameClock` turns it into the
/// frame age the probe compares stamps with): a cell of key 3 last used at t = 0.5 s is not taken over by a
/// key of its run (a full table: stale slots first) at any frame up to t + lifetime, and is taken over once it is
/// older than the lifetime plus one checkpoint interval and one frame. Catches a lifetime counted in frames
/// (240 frames: taken over after 1.7 s at 144 fps, kept for 24 s at 10 fps).
#[test]
fn a_cell_outlives_its_lifetime_in_seconds_at_10_and_144_fps() {
    const LIFETIME_S: f64 = 4.0;
    for fps in [10.0, 144.0] {
        let used = (0.5 * fps) as u32;
        let t_used = used as f64 / fps;
        let slack = LIFETIME_S / 64.0 + 1.0 / fps;
        let mut clock = FrameClock::new();
        let (mut last_kept, mut first_taken) = (None, None);
        for i in 0..(3.0 * LIFETIME_S * fps) as u32 {
            let now = i as f64 / fps;
            let f = Frame {
                frame_index: i,
                f_start_frame: 0,
                lifetime_frames: clock.lifetime_frames(i, now, LIFETIME_S),
                max_probe: 4,
                room: false,
            };
            if i <= used {
                continue;
            }
            let taken = reclaimable(&f, stamp(3, used));
            let age = now - t_used;
            assert!(
                !(taken && age <= LIFETIME_S),
                "{fps} fps: taken over {age:.3} s after its use"
            );
            assert!(
                taken || age <= LIFETIME_S + slack,
                "{fps} fps: kept {age:.3} s after its use"
            );
            if taken {
                first_taken.get_or_insert(f);
            } else {
                last_kept = Some(f);
            }
        }
        // The probe itself at both frames: key 5 (same home) finds the cell live, then takes it over.
        let init = [stamp(3, used), 0, 0, 0, 0, 0, 0, 0];
        assert_eq!(
            insert_alone(last_kept.unwrap(), &init, 0, 5).0,
            1,
            "{fps} fps: last frame within the lifetime"
        );
        assert_eq!(
            insert_alone(first_taken.unwrap(), &init, 0, 5).0,
            0,
            "{fps} fps: first frame past it"
        );
    }
}
