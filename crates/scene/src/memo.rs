//! Stable-step estimates kept between runs: a directory of small text files, one a Lanczos
//! iteration, named by the key the operator itself writes
//! ([`perifrac_physics::lanczos_frequency_of`]). A run of a scene whose model was built
//! before recalls its estimate after one force evaluation (two for a model that cannot vouch
//! for its forces at rest) instead of running the iteration again, and gets the same bits, so
//! its output is the same file for file.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use perifrac_physics::{EstimateMemo, FrequencyEstimate, MemoKey};

/// Environment variable naming the memo directory (it wins over the defaults).
pub const CACHE_ENV: &str = "PERIFRAC_CACHE";

/// A directory of stable-step estimates. Reads that fail or find a damaged file are misses;
/// the first store that fails is kept for the caller to report ([`MemoDir::failure`]).
#[derive(Debug)]
pub struct MemoDir {
    dir: PathBuf,
    failure: Mutex<Option<String>>,
}

impl MemoDir {
    /// A memo in `dir` (created on the first store).
    pub fn new(dir: impl Into<PathBuf>) -> MemoDir {
        MemoDir {
            dir: dir.into(),
            failure: Mutex::new(None),
        }
    }

    /// The user's cache directory for perifrac: `$PERIFRAC_CACHE`, else
    /// `$XDG_CACHE_HOME/perifrac`, else `$HOME/.cache/perifrac`; `None` when none is set.
    pub fn default_dir() -> Option<PathBuf> {
        let set = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
        set(CACHE_ENV)
            .map(PathBuf::from)
            .or_else(|| set("XDG_CACHE_HOME").map(|d| Path::new(&d).join("perifrac")))
            .or_else(|| set("HOME").map(|d| Path::new(&d).join(".cache").join("perifrac")))
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The first store that failed, as a message naming the file, if any did.
    pub fn failure(&self) -> Option<String> {
        self.failure.lock().map_or(None, |f| f.clone())
    }

    fn path(&self, key: MemoKey) -> PathBuf {
        self.dir.join(format!("stable-step-{}.txt", key.hex()))
    }
}

/// The file's lines: `omega_max`, `last_change` as the hex of their bits (exact), the counts
/// in decimal.
fn encode(est: &FrequencyEstimate) -> String {
    format!(
        "perifrac stable-step estimate\nomega_max {:016x}\niterations {}\nevaluations {}\n\
         last_change {:016x}\n",
        est.omega_max.to_bits(),
        est.iterations,
        est.evaluations,
        est.last_change.to_bits()
    )
}

fn decode(text: &str) -> Option<FrequencyEstimate> {
    let mut lines = text.lines();
    if lines.next()? != "perifrac stable-step estimate" {
        return None;
    }
    let mut field = |name: &str| {
        let line = lines.next()?;
        line.strip_prefix(name)?
            .strip_prefix(' ')
            .map(str::to_owned)
    };
    let bits = |s: String| u64::from_str_radix(&s, 16).ok().map(f64::from_bits);
    let omega_max = bits(field("omega_max")?)?;
    let iterations = field("iterations")?.parse().ok()?;
    let evaluations = field("evaluations")?.parse().ok()?;
    let last_change = bits(field("last_change")?)?;
    (omega_max.is_finite() && omega_max > 0.0).then_some(FrequencyEstimate {
        omega_max,
        iterations,
        evaluations,
        last_change,
        recalled: false,
    })
}

impl EstimateMemo for MemoDir {
    fn recall(&self, key: MemoKey) -> Option<FrequencyEstimate> {
        decode(&std::fs::read_to_string(self.path(key)).ok()?)
    }

    fn store(&self, key: MemoKey, estimate: &FrequencyEstimate) {
        let path = self.path(key);
        let result = std::fs::create_dir_all(&self.dir)
            .map_err(|e| format!("{}: {e}", self.dir.display()))
            .and_then(|()| {
                perifrac_io::atomic_write(&path, |w| {
                    std::io::Write::write_all(w, encode(estimate).as_bytes())
                })
                .map_err(|e| e.to_string())
            });
        if let (Err(message), Ok(mut failure)) = (result, self.failure.lock()) {
            failure.get_or_insert(message);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate() -> FrequencyEstimate {
        FrequencyEstimate {
            omega_max: 1.234_567_890_123_456_7e6,
            iterations: 17,
            evaluations: 18,
            last_change: 2.2e-7,
            recalled: false,
        }
    }

    #[test]
    fn an_estimate_comes_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let memo = MemoDir::new(dir.path().join("deeper"));
        let key = MemoKey([1, 2]);
        assert_eq!(memo.recall(key), None);
        memo.store(key, &estimate());
        assert_eq!(memo.recall(key), Some(estimate()));
        assert_eq!(memo.recall(MemoKey([1, 3])), None);
        assert_eq!(memo.failure(), None);
    }

    #[test]
    fn a_damaged_file_is_a_miss() {
        let dir = tempfile::tempdir().unwrap();
        let memo = MemoDir::new(dir.path());
        let key = MemoKey([7, 7]);
        memo.store(key, &estimate());
        let path = memo.path(key);
        let text = std::fs::read_to_string(&path).unwrap();
        for damaged in [
            text.replace("omega_max ", "omega_max x"),
            text.replace("perifrac", "other"),
            text.lines().take(3).collect::<Vec<_>>().join("\n"),
            // a zero frequency is never a stable step
            text.replace(&format!("{:016x}", estimate().omega_max.to_bits()), "0"),
        ] {
            std::fs::write(&path, damaged).unwrap();
            assert_eq!(memo.recall(key), None);
        }
    }

    #[test]
    fn a_store_that_fails_is_reported_once_and_the_run_goes_on() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a file");
        std::fs::write(&file, "").unwrap();
        let memo = MemoDir::new(&file);
        memo.store(MemoKey([1, 1]), &estimate());
        memo.store(MemoKey([2, 2]), &estimate());
        let failure = memo
            .failure()
            .expect("a directory under a file cannot be made");
        assert!(failure.contains("a file"), "{failure}");
        assert_eq!(memo.recall(MemoKey([1, 1])), None);
    }
}
