//! Live feedback while a run or sweep works: progress bars for long nodes, the frame range
//! and a sweep's runs (indicatif, on a terminal only), node log lines printed as they are
//! written, and the `-q` / `-v` levels. Off a terminal (a pipe, a log file, a cluster job)
//! bars become plain lines, printed only once something has run for a few seconds, so short
//! runs stay as quiet as before.

use crate::node::{LogFn, LogLevel, ProgressFn, PROGRESS_UNKNOWN};
use crate::sweep::SweepProgress;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::HashMap;
use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How much the command line prints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verbosity {
    /// `-q`: errors only.
    Quiet,
    /// Warnings, node logs, written files, one summary line per frame.
    Normal,
    /// `-v`: also each node's status and time, and nodes' debug lines.
    Verbose,
}

impl Verbosity {
    /// From the `-q` / `-v` flags (quiet wins).
    pub fn from_flags(quiet: bool, verbose: bool) -> Verbosity {
        match (quiet, verbose) {
            (true, _) => Verbosity::Quiet,
            (false, true) => Verbosity::Verbose,
            _ => Verbosity::Normal,
        }
    }
}

/// Off a terminal, progress lines start after this long (`CGNODES_PROGRESS_AFTER` seconds
/// overrides it; 0 prints them for every task).
fn plain_after() -> Duration {
    std::env::var("CGNODES_PROGRESS_AFTER")
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .map(Duration::from_secs_f64)
        .unwrap_or(Duration::from_secs(3))
}

/// One task being followed: a node, the frame range or a sweep.
struct Task {
    bar: Option<ProgressBar>,
    started: Instant,
    /// Last tenth printed as a plain line.
    tenth: i64,
}

struct Shared {
    tasks: HashMap<String, Task>,
    prefix: String,
}

/// Bars and live lines for one command (see the module doc).
#[derive(Clone)]
pub struct Monitor {
    level: Verbosity,
    bars: Option<MultiProgress>,
    plain_after: Duration,
    shared: Arc<Mutex<Shared>>,
}

impl Monitor {
    /// Bars when stderr is a terminal (and `CI` is unset), plain lines otherwise.
    pub fn new(level: Verbosity) -> Monitor {
        let tty = std::io::stderr().is_terminal() && std::env::var_os("CI").is_none();
        let bars = (tty && level > Verbosity::Quiet)
            .then(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr()));
        Monitor {
            level,
            bars,
            plain_after: plain_after(),
            shared: Arc::new(Mutex::new(Shared {
                tasks: HashMap::new(),
                prefix: String::new(),
            })),
        }
    }

    /// The verbosity.
    pub fn level(&self) -> Verbosity {
        self.level
    }

    /// Sets the prefix of live lines (`[frame N] ` over a frame range).
    pub fn set_prefix(&self, prefix: String) {
        self.lock().prefix = prefix;
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Prints a line without breaking the bars.
    pub fn println(&self, line: &str) {
        match &self.bars {
            Some(mp) => mp.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }

    /// Runs `f` (which prints) with the bars hidden.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        match &self.bars {
            Some(mp) => mp.suspend(f),
            None => f(),
        }
    }

    /// The node log sink of a run: lines at or above the level, as they are written.
    pub fn log_fn(&self) -> Option<LogFn> {
        if self.level == Verbosity::Quiet {
            return None;
        }
        let me = self.clone();
        Some(Arc::new(move |node: &str, level: LogLevel, line: &str| {
            if level == LogLevel::Debug && me.level < Verbosity::Verbose {
                return;
            }
            let prefix = me.lock().prefix.clone();
            me.println(&format!("{prefix}{node}: {line}"));
        }))
    }

    /// The node progress sink of a run.
    pub fn progress_fn(&self) -> Option<ProgressFn> {
        if self.level == Verbosity::Quiet {
            return None;
        }
        let me = self.clone();
        Some(Arc::new(move |node: &str, f: f64| {
            me.update(node, f, |_| String::new())
        }))
    }

    /// Starts following the frames `f0..=f1` (nothing for a single frame).
    pub fn start_frames(&self, f0: i64, f1: i64) {
        if f1 > f0 {
            self.start_counted("frames", (f1 - f0 + 1) as u64, "frames");
        }
    }

    /// One more frame done.
    pub fn frame_done(&self, f0: i64, f1: i64, frame: i64) {
        if f1 > f0 {
            let (done, total) = ((frame - f0 + 1) as u64, (f1 - f0 + 1) as u64);
            self.count("frames", done, total, "frames");
        }
    }

    /// A sweep's progress callback (runs done of runs in total, with an estimate of the time
    /// left).
    pub fn sweep_progress(&self) -> Option<SweepProgress> {
        if self.level == Verbosity::Quiet {
            return None;
        }
        let me = self.clone();
        Some(SweepProgress(Arc::new(move |done, total| {
            if done == 0 {
                me.start_counted("sweep", total as u64, "runs");
            } else {
                me.count("sweep", done as u64, total as u64, "runs");
            }
        })))
    }

    fn start_counted(&self, name: &str, len: u64, unit: &str) {
        let bar = self.bars.as_ref().map(|mp| {
            let b = mp.add(ProgressBar::new(len));
            let tpl = format!("{{prefix:>16}} {{bar:30}} {{pos}}/{{len}} {unit}, {{elapsed}} elapsed, ETA {{eta}}");
            if let Ok(st) = ProgressStyle::with_template(&tpl) {
                b.set_style(st);
            }
            b.set_prefix(name.to_string());
            b
        });
        self.lock().tasks.insert(
            name.to_string(),
            Task {
                bar,
                started: Instant::now(),
                tenth: 0,
            },
        );
    }

    fn count(&self, name: &str, done: u64, total: u64, unit: &str) {
        let f = done as f64 / total.max(1) as f64;
        self.update(name, f, |t| {
            let el = t.started.elapsed().as_secs_f64();
            let eta = if done > 0 {
                el * (total - done.min(total)) as f64 / done as f64
            } else {
                0.0
            };
            format!(" ({done}/{total} {unit}, ETA {eta:.0} s)")
        });
        if done >= total {
            if let Some(t) = self.lock().tasks.remove(name) {
                if let Some(b) = t.bar {
                    b.finish_and_clear();
                }
            }
        }
    }

    /// Moves task `name` to fraction `f` (or `PROGRESS_UNKNOWN`: a spinner); 1 ends it.
    fn update(&self, name: &str, f: f64, detail: impl Fn(&Task) -> String) {
        let mut sh = self.lock();
        if f >= 1.0 && !sh.tasks.contains_key(name) {
            // The executor ends every node's task; most never started one.
            return;
        }
        let prefix = sh.prefix.clone();
        let bars = self.bars.clone();
        let t = sh.tasks.entry(name.to_string()).or_insert_with(|| Task {
            bar: bars
                .as_ref()
                .map(|mp| node_bar(mp, name, f == PROGRESS_UNKNOWN)),
            started: Instant::now(),
            tenth: 0,
        });
        if let Some(b) = &t.bar {
            if f != PROGRESS_UNKNOWN {
                b.set_position((f.clamp(0.0, 1.0) * b.length().unwrap_or(1000) as f64) as u64);
            }
        } else if f != PROGRESS_UNKNOWN && t.started.elapsed() >= self.plain_after {
            // Plain lines: one per tenth, once the task has run for a while.
            let tenth = (f.clamp(0.0, 1.0) * 10.0).floor() as i64;
            if tenth > t.tenth {
                t.tenth = tenth;
                eprintln!(
                    "{prefix}{name}: {}% after {:.1} s{}",
                    tenth * 10,
                    t.started.elapsed().as_secs_f64(),
                    detail(t)
                );
            }
        }
        if f >= 1.0 {
            if let Some(t) = sh.tasks.remove(name) {
                if let Some(b) = t.bar {
                    b.finish_and_clear();
                }
            }
        }
    }
}

/// A node's bar: a percentage, or a spinner with the elapsed time when the fraction is
/// unknown (plugins).
fn node_bar(mp: &MultiProgress, node: &str, spinner: bool) -> ProgressBar {
    let (b, tpl) = if spinner {
        let b = mp.add(ProgressBar::new_spinner());
        b.enable_steady_tick(Duration::from_millis(120));
        (b, "{prefix:>16} {spinner} running, {elapsed}")
    } else {
        (
            mp.add(ProgressBar::new(1000)),
            "{prefix:>16} {bar:30} {percent:>3}% {elapsed}, ETA {eta}",
        )
    };
    if let Ok(st) = ProgressStyle::with_template(tpl) {
        b.set_style(st);
    }
    b.set_prefix(node.to_string());
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_map_to_levels() {
        assert_eq!(Verbosity::from_flags(true, true), Verbosity::Quiet);
        assert_eq!(Verbosity::from_flags(false, true), Verbosity::Verbose);
        assert_eq!(Verbosity::from_flags(false, false), Verbosity::Normal);
    }

    #[test]
    fn quiet_has_no_sinks_and_finished_tasks_are_dropped() {
        let q = Monitor::new(Verbosity::Quiet);
        assert!(q.log_fn().is_none() && q.progress_fn().is_none() && q.sweep_progress().is_none());
        let m = Monitor::new(Verbosity::Normal);
        let p = m.progress_fn().expect("a sink");
        p("a", 0.5);
        assert!(m.lock().tasks.contains_key("a"));
        p("a", 1.0);
        assert!(!m.lock().tasks.contains_key("a"));
        let s = m.sweep_progress().expect("a sink");
        (s.0)(0, 2);
        (s.0)(1, 2);
        assert!(m.lock().tasks.contains_key("sweep"));
        (s.0)(2, 2);
        assert!(!m.lock().tasks.contains_key("sweep"));
    }
}
