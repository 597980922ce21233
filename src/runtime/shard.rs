//! Splitting work between the processes of a cluster job: `--shard I/N` makes one process run
//! only its share, so that a Slurm job array or a Kubernetes Indexed Job runs the whole.
//! Frame ranges split into contiguous blocks (block I of N); sweep combinations round robin
//! (index mod N = I), which spreads the slow corners of a parameter grid over the shards.
//! `--shard auto` reads the shard from the engine's environment.

use std::ops::Range;

/// One share of the work: shard `index` of `count` (`0 <= index < count`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This process's shard, from 0.
    pub index: usize,
    /// How many shards there are.
    pub count: usize,
}

/// Why `--shard`/`--shards` (or the engine's environment for `--shard auto`) give no shard.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// `N` is 0.
    #[error("--shard: the number of shards must be at least 1")]
    NoShards,
    /// `I >= N`.
    #[error("--shard {index}/{count}: the shard index counts from 0 and must be below {count}")]
    IndexTooLarge {
        /// The index given.
        index: usize,
        /// The number of shards.
        count: usize,
    },
    /// Not of the form `I/N`.
    #[error("--shard '{0}': expected I/N (for example 0/4) or auto")]
    Syntax(String),
    /// `I` or `N` is not a whole number.
    #[error("--shard '{0}': expected I/N with whole numbers I >= 0, N >= 1")]
    NotWhole(String),
    /// `--shard I/N` with a `--shards` other than `N`.
    #[error("--shard {shard} and --shards {shards} disagree on the number of shards")]
    Disagree {
        /// The shard given.
        shard: Shard,
        /// `--shards`.
        shards: usize,
    },
    /// `--shards` without `--shard`.
    #[error("--shards needs --shard auto (or --shard I/N)")]
    ShardsAlone,
    /// An environment variable that is not a whole number.
    #[error("--shard auto: {name}='{value}' is not a whole number >= 0")]
    EnvNotWhole {
        /// The variable.
        name: String,
        /// Its value.
        value: String,
    },
    /// A Slurm task id without the array's size.
    #[error("--shard auto: SLURM_ARRAY_TASK_ID is set but neither SLURM_ARRAY_TASK_COUNT nor SLURM_ARRAY_TASK_MIN/MAX")]
    SlurmNoCount,
    /// A Slurm task id off the array's min and step.
    #[error("--shard auto: SLURM_ARRAY_TASK_ID={id} is not in the array (min {min}, step {step})")]
    NotInArray {
        /// `SLURM_ARRAY_TASK_ID`.
        id: usize,
        /// `SLURM_ARRAY_TASK_MIN`.
        min: usize,
        /// `SLURM_ARRAY_TASK_STEP`.
        step: usize,
    },
    /// A Slurm array size other than `--shards`.
    #[error("--shard auto: the Slurm array has {count} tasks but --shards says {shards}")]
    SlurmDisagree {
        /// The array's tasks.
        count: usize,
        /// `--shards`.
        shards: usize,
    },
    /// A Kubernetes completion index without the number of shards.
    #[error("--shard auto: JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job) but not the number of shards: give --shards N (the Job's completions) or set CGNODES_SHARDS")]
    KubernetesNoCount,
    /// `--shard auto` outside a job array.
    #[error("--shard auto: no shard in the environment (SLURM_ARRAY_TASK_ID for a Slurm job array, JOB_COMPLETION_INDEX for a Kubernetes Indexed Job); give --shard I/N")]
    NoEnvironment,
}

impl Default for Shard {
    fn default() -> Shard {
        Shard::ALL
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// The whole of the work in one shard.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// A shard, checked: `count >= 1` and `index < count`.
    pub fn new(index: usize, count: usize) -> Result<Shard, ShardError> {
        if count == 0 {
            return Err(ShardError::NoShards);
        }
        if index >= count {
            return Err(ShardError::IndexTooLarge { index, count });
        }
        Ok(Shard { index, count })
    }

    /// Parses `I/N` (`--shard 2/8`).
    pub fn parse(s: &str) -> Result<Shard, ShardError> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| ShardError::Syntax(s.into()))?;
        let num = |t: &str| {
            t.trim()
                .parse::<usize>()
                .map_err(|_| ShardError::NotWhole(s.into()))
        };
        Shard::new(num(i)?, num(n)?)
    }

    /// Reads `--shard`: `I/N`, or `auto` for the environment (see `from_env`). `shards` is
    /// `--shards N`; `env` looks a variable up (the process environment in the command line,
    /// a map in tests).
    pub fn resolve(
        arg: &str,
        shards: Option<usize>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Shard, ShardError> {
        if arg.trim() == "auto" {
            Shard::from_env(shards, env)
        } else {
            let s = Shard::parse(arg)?;
            match shards {
                Some(n) if n != s.count => Err(ShardError::Disagree {
                    shard: s,
                    shards: n,
                }),
                _ => Ok(s),
            }
        }
    }

    /// The shard of this process from its engine's environment: a Slurm job array
    /// (`SLURM_ARRAY_TASK_ID` with `SLURM_ARRAY_TASK_COUNT`, or `SLURM_ARRAY_TASK_MIN`/`MAX`;
    /// `SLURM_ARRAY_TASK_STEP` for arrays like `0-6:2`), or a Kubernetes Indexed Job
    /// (`JOB_COMPLETION_INDEX`, with the number of shards from `shards` or `CGNODES_SHARDS`,
    /// since the pod does not see `completions`).
    pub fn from_env(
        shards: Option<usize>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Shard, ShardError> {
        let num = |name: &str| -> Result<Option<usize>, ShardError> {
            match env(name) {
                None => Ok(None),
                Some(v) if v.trim().is_empty() => Ok(None),
                Some(v) => {
                    v.trim()
                        .parse::<usize>()
                        .map(Some)
                        .map_err(|_| ShardError::EnvNotWhole {
                            name: name.into(),
                            value: v,
                        })
                }
            }
        };
        if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = num("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let count = match (num("SLURM_ARRAY_TASK_COUNT")?, num("SLURM_ARRAY_TASK_MAX")?) {
                (Some(c), _) => c,
                (None, Some(max)) if max >= min => (max - min) / step + 1,
                _ => return Err(ShardError::SlurmNoCount),
            };
            if id < min || (id - min) % step != 0 {
                return Err(ShardError::NotInArray { id, min, step });
            }
            let s = Shard::new((id - min) / step, count)?;
            return match shards {
                Some(n) if n != count => Err(ShardError::SlurmDisagree { count, shards: n }),
                _ => Ok(s),
            };
        }
        if let Some(i) = num("JOB_COMPLETION_INDEX")? {
            let n = match shards {
                Some(n) => n,
                None => num("CGNODES_SHARDS")?.ok_or(ShardError::KubernetesNoCount)?,
            };
            return Shard::new(i, n);
        }
        Err(ShardError::NoEnvironment)
    }

    /// This shard's contiguous block of `0..len`: blocks of sizes differing by at most one,
    /// in order, so that shard 0 gets the first frames.
    pub fn block(&self, len: u64) -> Range<u64> {
        let (i, n, len) = (self.index as u128, self.count as u128, len as u128);
        ((i * len / n) as u64)..(((i + 1) * len / n) as u64)
    }

    /// This shard's frames of the inclusive range `first..=last`, or `None` when it gets none
    /// (more shards than frames).
    pub fn frames(&self, first: i64, last: i64) -> Option<(i64, i64)> {
        if last < first {
            return None;
        }
        let len = (last as i128 - first as i128 + 1) as u64;
        let b = self.block(len);
        (b.start < b.end).then(|| {
            (
                (first as i128 + b.start as i128) as i64,
                (first as i128 + b.end as i128 - 1) as i64,
            )
        })
    }

    /// Whether this shard runs the sweep combination with index `k` (round robin).
    pub fn takes(&self, k: usize) -> bool {
        k % self.count == self.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let m: HashMap<String, String> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| m.get(k).cloned()
    }

    #[test]
    fn every_frame_and_combination_falls_in_exactly_one_shard() {
        for n in 1..=7 {
            for len in 0..=50u64 {
                let mut frame_seen = vec![0; len as usize];
                let mut combo_seen = vec![0; len as usize];
                let mut next = 0;
                let mut sizes = Vec::new();
                for i in 0..n {
                    let s = Shard::new(i, n).unwrap();
                    let b = s.block(len);
                    // Blocks are contiguous and in shard order.
                    assert_eq!(b.start, next, "n={n} len={len} i={i}");
                    next = b.end;
                    sizes.push(b.end - b.start);
                    for f in b {
                        frame_seen[f as usize] += 1;
                    }
                    for (k, c) in combo_seen.iter_mut().enumerate() {
                        if s.takes(k) {
                            *c += 1;
                        }
                    }
                    // The same block on an inclusive frame range starting anywhere.
                    if len > 0 {
                        let r = s.frames(-3, -3 + len as i64 - 1);
                        let b = s.block(len);
                        let want =
                            (b.start < b.end).then(|| (-3 + b.start as i64, -3 + b.end as i64 - 1));
                        assert_eq!(r, want);
                    }
                }
                assert_eq!(next, len);
                assert!(frame_seen.iter().all(|&c| c == 1), "n={n} len={len}");
                assert!(combo_seen.iter().all(|&c| c == 1), "n={n} len={len}");
                // Balanced: block sizes differ by at most one.
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "n={n} len={len} {sizes:?}");
            }
        }
        // Frames 1..=10 in 3 shards: 1..=3, 4..=6, 7..=10 (hand-computed floor(i*10/3)).
        let f: Vec<_> = (0..3)
            .map(|i| Shard::new(i, 3).unwrap().frames(1, 10))
            .collect();
        assert_eq!(f, vec![Some((1, 3)), Some((4, 6)), Some((7, 10))]);
        assert_eq!(Shard::new(3, 4).unwrap().frames(5, 7), Some((7, 7)));
        assert_eq!(Shard::new(0, 4).unwrap().frames(5, 7), None);
        assert_eq!(Shard::new(1, 2).unwrap().frames(5, 4), None);
    }

    #[test]
    fn shards_parse_with_clear_errors() {
        assert_eq!(Shard::parse("2/8"), Ok(Shard { index: 2, count: 8 }));
        assert_eq!(Shard::parse(" 0 / 1 "), Ok(Shard::ALL));
        for bad in ["3", "8/8", "1/0", "-1/4", "a/4", "1/b", "", "1/2/3"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--shard"), "{bad}: {e}");
        }
        assert!(Shard::parse("8/8")
            .unwrap_err()
            .to_string()
            .contains("below 8"));
        assert!(Shard::resolve("1/4", Some(3), env(&[]))
            .unwrap_err()
            .to_string()
            .contains("disagree"));
        assert_eq!(Shard::resolve("1/4", Some(4), env(&[])), Shard::new(1, 4));
    }

    #[test]
    fn auto_reads_slurm_and_kubernetes_environments() {
        let auto = |shards, pairs: &[(&str, &str)]| Shard::resolve("auto", shards, env(pairs));
        // Slurm, --array=0-3.
        let s = auto(
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ],
        );
        assert_eq!(s, Shard::new(2, 4));
        // Slurm, --array=1-5 with only MIN/MAX: task 1 is shard 0.
        let s = auto(
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "1"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "5"),
            ],
        );
        assert_eq!(s, Shard::new(0, 5));
        // Slurm, --array=0-6:2 (tasks 0, 2, 4, 6): task 4 is shard 2 of 4.
        let s = auto(
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "4"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_MAX", "6"),
                ("SLURM_ARRAY_TASK_STEP", "2"),
            ],
        );
        assert_eq!(s, Shard::new(2, 4));
        // Slurm with a --shards that disagrees.
        assert!(auto(
            Some(3),
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "4")
            ]
        )
        .unwrap_err()
        .to_string()
        .contains("4 tasks"));
        // Slurm without a count.
        assert!(auto(None, &[("SLURM_ARRAY_TASK_ID", "0")])
            .unwrap_err()
            .to_string()
            .contains("SLURM_ARRAY_TASK_COUNT"));
        assert!(auto(
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "x"),
                ("SLURM_ARRAY_TASK_COUNT", "4")
            ]
        )
        .unwrap_err()
        .to_string()
        .contains("whole number"));
        // Kubernetes with --shards, with CGNODES_SHARDS, and with neither.
        assert_eq!(
            auto(Some(6), &[("JOB_COMPLETION_INDEX", "5")]),
            Shard::new(5, 6)
        );
        assert_eq!(
            auto(
                None,
                &[("JOB_COMPLETION_INDEX", "1"), ("CGNODES_SHARDS", "3")]
            ),
            Shard::new(1, 3)
        );
        assert!(auto(None, &[("JOB_COMPLETION_INDEX", "1")])
            .unwrap_err()
            .to_string()
            .contains("--shards N"));
        assert!(auto(Some(2), &[("JOB_COMPLETION_INDEX", "2")])
            .unwrap_err()
            .to_string()
            .contains("below 2"));
        // Nothing set.
        let e = auto(Some(4), &[]).unwrap_err().to_string();
        assert!(e.contains("SLURM_ARRAY_TASK_ID") && e.contains("JOB_COMPLETION_INDEX"));
    }
}
