//! Reload on change: the open file's directory is watched through the OS (`notify`: inotify on Linux, so a
//! quiet file costs no CPU, and an editor's save-by-rename is seen as well as a write in place). An event for the
//! file starts a short look at its size and modification time, and once a change has been quiet for `QUIET`
//! (exporters write in pieces) it is flagged and egui is asked for a repaint, which wakes the event loop once.
//! The viewer then reloads (`reload.rs`). The debounce is a pure state machine (`Debounce`), unit tested.
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

use notify::{RecursiveMode, Watcher};

/// How long a changed file must stay unchanged before it is reloaded.
pub const QUIET: Duration = Duration::from_millis(300);
/// How often a changing file is looked at until it is quiet (only while a change is pending).
const SETTLE_POLL: Duration = Duration::from_millis(100);

/// What is compared: the file's size and modification time (None: the file is not there).
pub type Signature = Option<(u64, Option<SystemTime>)>;

pub fn signature(path: &Path) -> Signature {
    let m = std::fs::metadata(path).ok()?;
    Some((m.len(), m.modified().ok()))
}

/// Fires once per change, after the file has kept a new signature for `quiet`. A file that disappears (an
/// exporter deleting before writing) fires nothing until it is back.
pub struct Debounce {
    seen: Signature,
    pending: Option<(Signature, Instant)>,
    quiet: Duration,
}

impl Debounce {
    pub fn new(current: Signature, quiet: Duration) -> Debounce {
        Debounce {
            seen: current,
            pending: None,
            quiet,
        }
    }

    /// A change seen and not yet settled (or a missing file waiting to come back).
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// The file's signature at `now`: true when a change has settled.
    pub fn observe(&mut self, sig: Signature, now: Instant) -> bool {
        if sig == self.seen {
            self.pending = None;
            return false;
        }
        match self.pending {
            Some((p, since)) if p == sig => {
                if sig.is_some() && now.duration_since(since) >= self.quiet {
                    self.seen = sig;
                    self.pending = None;
                    return true;
                }
                false
            }
            _ => {
                self.pending = Some((sig, now));
                false
            }
        }
    }
}

/// The watch on the open file. Dropping it drops the OS watch, whose event channel then closes and ends the
/// thread.
pub struct FileWatch {
    pub path: PathBuf,
    changed: Arc<AtomicBool>,
    _watcher: notify::RecommendedWatcher,
}

impl FileWatch {
    /// Watches `path` from its state now; `wake` is called (from the thread) when a change has settled. An error
    /// (no such directory, the OS's watch limit reached) says why the file cannot be watched.
    pub fn start(path: PathBuf, wake: impl Fn() + Send + 'static) -> notify::Result<FileWatch> {
        let changed = Arc::new(AtomicBool::new(false));
        let dir = path.parent().unwrap_or(Path::new("/")).to_path_buf();
        let name = path.file_name().map(|n| n.to_os_string());
        let (tx, rx) = mpsc::channel();
        let mut watcher = notify::recommended_watcher(move |event: notify::Result<notify::Event>| {
            // Events for the file itself, and those the OS could not attribute (a rescan after an overflow).
            let ours = match &event {
                Ok(e) => e.paths.is_empty() || e.paths.iter().any(|p| p.file_name() == name.as_deref()),
                Err(_) => true,
            };
            if ours {
                let _ = tx.send(());
            }
        })?;
        // The directory, not the file: a save by rename replaces the file's inode, which a watch on it would lose.
        watcher.watch(&dir, RecursiveMode::NonRecursive)?;
        let (c, p) = (changed.clone(), path.clone());
        let mut debounce = Debounce::new(signature(&path), QUIET);
        std::thread::Builder::new()
            .name("file-watch".into())
            .spawn(move || {
                // Blocks until the file is touched; ends when the watcher (the sender) is dropped.
                while rx.recv().is_ok() {
                    loop {
                        let sig = signature(&p);
                        if debounce.observe(sig, Instant::now()) {
                            log::info!("file changed on disk: {}", p.display());
                            c.store(true, Ordering::Relaxed);
                            wake();
                            break;
                        }
                        // Nothing pending, or the file is gone: its return is an event of its own.
                        if !debounce.is_pending() || sig.is_none() {
                            break;
                        }
                        // Further events only restart the look; the quiet time is the signature's.
                        if let Err(RecvTimeoutError::Disconnected) = rx.recv_timeout(SETTLE_POLL) {
                            return;
                        }
                    }
                }
            })?;
        Ok(FileWatch {
            path,
            changed,
            _watcher: watcher,
        })
    }

    /// A settled change since the last call.
    pub fn take_change(&self) -> bool {
        self.changed.swap(false, Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_fires_once_after_it_has_been_quiet() {
        let t0 = Instant::now();
        let ms = |m: u64| t0 + Duration::from_millis(m);
        let sig = |n: u64| Some((n, None));
        let mut d = Debounce::new(sig(10), Duration::from_millis(300));
        assert!(!d.observe(sig(10), ms(0)), "unchanged");
        // Written in pieces: each new size restarts the quiet time.
        assert!(!d.observe(sig(20), ms(100)));
        assert!(!d.observe(sig(30), ms(250)));
        assert!(!d.observe(sig(30), ms(500)), "quiet for 250 ms only");
        assert!(d.observe(sig(30), ms(550)), "quiet for 300 ms");
        assert!(!d.observe(sig(30), ms(900)), "once per change");
        // Deleted, then written again: nothing while it is missing, one reload once it is back and quiet.
        assert!(!d.observe(None, ms(1000)));
        assert!(!d.observe(None, ms(2000)));
        assert!(!d.observe(sig(40), ms(2100)));
        assert!(d.observe(sig(40), ms(2400)));
        // Changed and changed back before it was quiet: no reload.
        assert!(!d.observe(sig(50), ms(3000)));
        assert!(!d.observe(sig(40), ms(3100)));
        assert!(!d.observe(sig(40), ms(4000)));
    }

    #[test]
    fn the_thread_flags_a_rewritten_file() {
        let path = std::env::temp_dir().join(format!("hrtao-watch-{}.obj", std::process::id()));
        std::fs::write(&path, "v 0 0 0\n").unwrap();
        let woken = Arc::new(AtomicBool::new(false));
        let w = woken.clone();
        let watch = FileWatch::start(path.clone(), move || w.store(true, Ordering::Relaxed)).unwrap();
        std::thread::sleep(Duration::from_millis(600));
        assert!(!watch.take_change(), "nothing changed");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\n").unwrap();
        let t0 = Instant::now();
        while !woken.load(Ordering::Relaxed) && t0.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(50));
        }
        assert!(watch.take_change() && woken.load(Ordering::Relaxed));
        assert!(!watch.take_change(), "taken once");
        drop(watch);
        let _ = std::fs::remove_file(&path);
    }
}
