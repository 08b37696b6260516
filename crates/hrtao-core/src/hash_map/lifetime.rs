//! eq. (6)'s lazy removal counted in seconds: a cell stamped at a frame (`HashCell::stamp`) may be reclaimed
//! once that frame is more than the cache lifetime (`MapSettings::cache_lifetime_s`) behind the current one.
//! Cells keep their frame stamps (one 64-bit word with the checksum: the single-CAS claim of hash_map.glsl), so
//! the host turns the lifetime into a frame age each frame, from the times of recent frames. Counted in frames,
//! a fixed age protected a cell for 24 s at 10 fps but 1.7 s at 144 fps; counted in time, a region revisited
//! within the lifetime finds its cells at any frame rate.
use std::collections::VecDeque;

/// A frame becomes a checkpoint when at least 1/this of the lifetime passed since the last one: a cell outlives
/// its lifetime by less than that (the frames between two checkpoints are only known to lie between their
/// times), and the ring holds about this many checkpoints plus one.
const CHECKPOINTS_PER_LIFETIME: f64 = 64.0;
/// The ring's bound whatever the lifetime does (a lifetime made shorter trims the ring on the next frame; one
/// made longer lets it grow to a lifetime's checkpoints). Dropping the oldest checkpoint only protects more.
const MAX_CHECKPOINTS: usize = 4 * CHECKPOINTS_PER_LIFETIME as usize;

/// `lifetime_frames` while no frame is older than the lifetime: no cell is reclaimed for its age.
pub const NO_AGE_LIMIT: u32 = u32::MAX;

/// The times of recent frames, sparse: enough to name, at every frame, the newest frame older than the lifetime.
#[derive(Debug, Default)]
pub struct FrameClock {
    /// (frame index, seconds), oldest first; times never decrease, and the frames between two checkpoints
    /// started less than a checkpoint interval after the first of them.
    checkpoints: VecDeque<(u32, f64)>,
    /// The time of the last frame (a clock that goes back is held at it).
    last_seconds: f64,
}

impl FrameClock {
    pub fn new() -> FrameClock {
        FrameClock::default()
    }

    /// Frame `frame` starts at `seconds` (of any fixed origin): returns the age in frames past which a cell is
    /// reclaimable (`FrameGlobals::lifetime_frames`, hash_map.glsl `stamp_reclaimable`: age > lifetime_frames):
    /// every frame stamped at or before the newest checkpoint older than `lifetime_s` started more than
    /// `lifetime_s` ago, and every frame after it is kept. NO_AGE_LIMIT while no checkpoint is that old (a
    /// fresh clock, or one whose lifetime just grew past its history).
    pub fn lifetime_frames(&mut self, frame: u32, seconds: f64, lifetime_s: f64) -> u32 {
        let now = if seconds.is_finite() {
            seconds.max(self.last_seconds)
        } else {
            self.last_seconds
        };
        self.last_seconds = now;
        let interval = lifetime_s / CHECKPOINTS_PER_LIFETIME;
        match self.checkpoints.back_mut() {
            // The same frame again (prepared twice): its later time only makes it look younger.
            Some(last) if last.0 == frame => last.1 = now,
            Some(last) if now - last.1 < interval => {}
            _ => self.checkpoints.push_back((frame, now)),
        }
        // Keep the newest checkpoint that is older than the lifetime at the front: it names the last frame that
        // may be reclaimed.
        while self.checkpoints.len() > MAX_CHECKPOINTS
            || self.checkpoints.get(1).is_some_and(|c| now - c.1 > lifetime_s)
        {
            self.checkpoints.pop_front();
        }
        self.frames_within(frame, lifetime_s)
    }

    /// After `lifetime_frames` for `frame`: the age in frames past which a cell was last used more than
    /// `seconds` ago, for `seconds` up to that call's lifetime (a shorter one under pressure, `TableLoad`).
    /// Frames between two checkpoints are kept: a cell outlives `seconds` by less than a checkpoint interval
    /// of that lifetime and a frame.
    pub fn frames_within(&self, frame: u32, seconds: f64) -> u32 {
        // Older than `seconds`: an age (not a time compared with now - seconds, which rounds differently).
        let now = self.last_seconds;
        match self.checkpoints.iter().rev().find(|c| now - c.1 > seconds) {
            Some(&(old, _)) => frame.wrapping_sub(old).wrapping_sub(1),
            None => NO_AGE_LIMIT,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// hash_map.glsl `stamp_reclaimable` for a cell of the current F.
    fn reclaimable(now: u32, stamped: u32, lifetime_frames: u32) -> bool {
        now.wrapping_sub(stamped) > lifetime_frames
    }

    /// At `fps` simulated frames per second, from frame `first` on (a frame index near the wrap in one case),
    /// a cell stamped at any frame is never reclaimable within the lifetime and is reclaimable once it is older
    /// than the lifetime plus one checkpoint interval and one frame. Catches a lifetime counted in frames (e.g.
    /// `lifetime_s * 60.0` frames, 240 frames for 4 s: reclaimed after 1.7 s at 144 fps, kept for 24 s at
    /// 10 fps) and a front checkpoint that is not the newest expired one (no `pop_front`: cells kept forever).
    fn check_rate(fps: f64, lifetime_s: f64, first: u32) {
        let mut clock = FrameClock::new();
        let frames = (3.0 * lifetime_s * fps) as u32;
        let slack = lifetime_s / CHECKPOINTS_PER_LIFETIME + 1.0 / fps;
        let time = |f: u32| f.wrapping_sub(first) as f64 / fps;
        let mut reclaimed_at_all = 0;
        for i in 0..frames {
            let now = first.wrapping_add(i);
            let lf = clock.lifetime_frames(now, time(now), lifetime_s);
            for back in 0..=i {
                let stamped = now.wrapping_sub(back);
                let age_s = time(now) - time(stamped);
                let r = reclaimable(now, stamped, lf);
                assert!(
                    !(r && age_s <= lifetime_s),
                    "{fps} fps: a cell used {age_s:.3} s ago is reclaimable within its {lifetime_s} s lifetime"
                );
                assert!(
                    r || age_s <= lifetime_s + slack,
                    "{fps} fps: a cell used {age_s:.3} s ago is still kept ({lifetime_s} s lifetime)"
                );
                reclaimed_at_all += r as u32;
            }
        }
        assert!(reclaimed_at_all > 0);
    }

    #[test]
    fn a_cell_is_kept_for_its_lifetime_and_no_longer_at_10_fps() {
        check_rate(10.0, 2.0, 0);
        check_rate(10.0, 0.35, u32::MAX - 5);
    }

    #[test]
    fn a_cell_is_kept_for_its_lifetime_and_no_longer_at_144_fps() {
        check_rate(144.0, 2.0, 0);
        check_rate(144.0, 0.35, u32::MAX - 100);
    }

    /// A lifetime made longer than the clock's history protects every cell until the history covers it; one made
    /// shorter applies at the next frame. A clock that goes back is held (cells never look older than they are).
    #[test]
    fn lifetime_changes_and_a_clock_that_goes_back_never_reclaim_early() {
        let mut clock = FrameClock::new();
        // Frames every 1/8 s (exact in binary).
        let t = |f: u32| f as f64 * 0.125;
        let mut lf = 0;
        for f in 0..100u32 {
            lf = clock.lifetime_frames(f, t(f), 1.0);
        }
        // Frame 99 at 12.375 s: frames up to 90 (11.25 s) are older than 1 s, frame 91 is exactly 1 s old.
        assert!(reclaimable(99, 90, lf) && !reclaimable(99, 91, lf), "{lf}");
        // Ten times longer: the history was trimmed to ~1 s, so no frame is known to be 10 s old.
        assert_eq!(clock.lifetime_frames(100, t(100), 10.0), NO_AGE_LIMIT);
        // Shorter again: applies at once (frame 97 is 0.5 s before frame 101).
        let lf = clock.lifetime_frames(101, t(101), 0.5);
        assert!(reclaimable(101, 96, lf) && !reclaimable(101, 97, lf), "{lf}");
        // The clock goes back 5 s: held at frame 101's time, so the same frames count as expired, no more.
        let back = clock.lifetime_frames(102, 5.0, 0.5);
        assert!(
            reclaimable(102, 96, back) && !reclaimable(102, 97, back),
            "{back}"
        );
        // A NaN time: held too.
        let nan = clock.lifetime_frames(103, f64::NAN, 0.5);
        assert!(reclaimable(103, 96, nan) && !reclaimable(103, 97, nan), "{nan}");
    }

    /// A shorter lifetime read from the ring of a longer one (pressure): a cell is kept for it, and reclaimable
    /// after it plus one checkpoint interval of the longer lifetime and a frame.
    #[test]
    fn a_shorter_lifetime_from_the_same_ring() {
        let mut clock = FrameClock::new();
        let fps = 144.0;
        let (long, short) = (4.0, 0.5);
        let slack = long / CHECKPOINTS_PER_LIFETIME + 1.0 / fps;
        for f in 0..(2.0 * long * fps) as u32 {
            let now = f as f64 / fps;
            clock.lifetime_frames(f, now, long);
            let lf = clock.frames_within(f, short);
            for back in 0..=f {
                let age = now - (f - back) as f64 / fps;
                let r = reclaimable(f, f - back, lf);
                assert!(!(r && age <= short), "reclaimed {age:.3} s after use");
                assert!(r || age <= short + slack, "kept {age:.3} s after use");
            }
        }
    }

    /// The ring stays small however many frames and whatever the frame rate.
    #[test]
    fn the_ring_stays_small() {
        let mut clock = FrameClock::new();
        for f in 0..100_000u32 {
            clock.lifetime_frames(f, f as f64 / 1000.0, 30.0);
            assert!(clock.checkpoints.len() <= CHECKPOINTS_PER_LIFETIME as usize + 3);
        }
    }
}
