//! Progress bars (indicatif) for the library's long-running phases, drawn on
//! stderr only when it is a terminal. A thread polls the counters of
//! `a3d_init::progress` and shows a bar for a phase once it has run a second.

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Draws while alive; dropping it stops the drawing and clears the bars.
pub struct Progress {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// Starts drawing progress bars when stderr is a terminal.
pub fn show() -> Option<Progress> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        let counters = a3d_init::progress::all();
        let mut state: Vec<(Option<Instant>, Option<ProgressBar>)> =
            counters.iter().map(|_| (None, None)).collect();
        while !flag.load(Ordering::Relaxed) {
            for (c, (since, bar)) in counters.iter().zip(state.iter_mut()) {
                let (done, total) = c.get();
                if total == 0 || done >= total {
                    if let Some(b) = bar.take() {
                        b.finish_and_clear();
                    }
                    *since = None;
                    continue;
                }
                let started = *since.get_or_insert_with(Instant::now);
                if started.elapsed() < Duration::from_secs(1) {
                    continue;
                }
                let b = bar.get_or_insert_with(|| {
                    let b = ProgressBar::new(total);
                    if let Ok(style) =
                        ProgressStyle::with_template("{msg:20} [{bar:40}] {percent:>3}%  {eta}")
                    {
                        b.set_style(style.progress_chars("=> "));
                    }
                    b.set_message(c.name());
                    b
                });
                b.set_length(total);
                b.set_position(done);
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        for (_, bar) in state {
            if let Some(b) = bar {
                b.finish_and_clear();
            }
        }
    });
    Some(Progress {
        stop,
        thread: Some(thread),
    })
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
