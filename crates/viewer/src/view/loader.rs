//! Opening a scene in the background: the loader thread (its progress, its cancel flag), and the last load
//! error for the panel. The window keeps drawing the current scene until the new one has loaded.
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use hrtao_scene::Scene;

use super::command::LoadingView;

/// Messages from the loader thread.
enum LoadMsg {
    Progress(String),
    Done(Result<Box<Scene>, String>, Duration),
}

struct Loading {
    spec: String,
    /// Its cancel flag stops the loader thread at its next chunk or mesh.
    opts: hrtao_scene::LoadOptions,
    rx: Receiver<LoadMsg>,
    progress: String,
    started: Instant,
}

/// A finished load: the scene or the error (naming the file and the reason), and how long it took.
pub struct Loaded {
    pub spec: String,
    pub result: Result<Scene, String>,
    pub took: Duration,
}

#[derive(Default)]
pub struct Loader {
    loading: Option<Loading>,
    /// The last load's error, until the next load starts.
    pub error: Option<String>,
}

impl Loader {
    /// Starts loading `spec` on a thread with `opts`; a load still running is cancelled.
    pub fn start(&mut self, spec: String, opts: hrtao_scene::LoadOptions) {
        self.cancel();
        log::info!("opening {spec}");
        let (tx, rx) = mpsc::channel();
        let s = spec.clone();
        let thread_opts = opts.clone();
        std::thread::spawn(move || {
            let t0 = Instant::now();
            let mut last = Instant::now() - Duration::from_secs(1);
            let ptx = tx.clone();
            let result = hrtao_scene::load_with(&s, &thread_opts, &mut |p| {
                if last.elapsed() > Duration::from_millis(100) {
                    last = Instant::now();
                    let _ = ptx.send(LoadMsg::Progress(progress_text(&p)));
                }
            })
            .map_err(|e| format!("cannot open `{s}`: {e}"));
            let _ = tx.send(LoadMsg::Done(result.map(Box::new), t0.elapsed()));
        });
        self.loading = Some(Loading {
            spec,
            opts,
            rx,
            progress: "starting".into(),
            started: Instant::now(),
        });
        self.error = None;
    }

    /// Stops the running load (its thread ends at its next step); returns what it was loading.
    pub fn cancel(&mut self) -> Option<String> {
        let l = self.loading.take()?;
        l.opts.cancel.store(true, std::sync::atomic::Ordering::Relaxed);
        Some(l.spec)
    }

    pub fn is_loading(&self) -> bool {
        self.loading.is_some()
    }

    /// The running load for the panels.
    pub fn view(&self) -> Option<LoadingView<'_>> {
        self.loading.as_ref().map(|l| LoadingView {
            spec: &l.spec,
            progress: &l.progress,
            seconds: l.started.elapsed().as_secs_f32(),
        })
    }

    /// Takes the loader's messages; the finished load, once.
    pub fn poll(&mut self) -> Option<Loaded> {
        let loading = self.loading.as_mut()?;
        let mut done = None;
        while let Ok(msg) = loading.rx.try_recv() {
            match msg {
                LoadMsg::Progress(p) => loading.progress = p,
                LoadMsg::Done(r, t) => done = Some((r.map(|s| *s), t)),
            }
        }
        let (result, took) = done?;
        let spec = self.loading.take()?.spec;
        Some(Loaded { spec, result, took })
    }
}

/// "read 40% of 12 MB", "meshes 10%", …
fn progress_text(p: &hrtao_scene::LoadProgress) -> String {
    let pct = if p.total > 0 {
        format!(" {:.0}%", 100.0 * p.done as f64 / p.total as f64)
    } else {
        String::new()
    };
    let mb = if p.stage == "read" {
        format!(" of {:.0} MB", p.total as f64 / 1e6)
    } else {
        String::new()
    };
    format!("{}{pct}{mb}", p.stage)
}
