//! The fuzz tests' driver (tests/fuzz_corpus.rs, fuzz_mutate.rs, fuzz_spirv.rs): their seeds, the
//! run's length and seed, the mutation RNG, and the panic counter.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// The files of `dir` (relative to the repository) that `keep` keeps, sorted, with their names
/// and bytes.
pub fn files(dir: &str, keep: impl Fn(&Path) -> bool) -> Vec<(String, Vec<u8>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && keep(p))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// How many mutations to run and from which seed: WEFT_FUZZ_ITERATIONS (3000 when unset, a few
/// seconds) and WEFT_FUZZ_SEED (1).
pub fn iterations_and_seed() -> (usize, u64) {
    let iterations: usize = std::env::var("WEFT_FUZZ_ITERATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000);
    let seed: u64 = std::env::var("WEFT_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    (iterations, seed)
}

/// xorshift64*: small, deterministic, good enough to choose mutations (the fuzz tests).
pub struct Rng(pub u64);

impl Rng {
    /// The mutation RNG of a run with seed `seed`.
    pub fn for_seed(seed: u64) -> Rng {
        Rng(0x9E37_79B9_7F4A_7C15 ^ seed.wrapping_mul(0xBF58_476D_1CE4_E5B9))
    }
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
    pub fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }
}

type Hook = Box<dyn Fn(&std::panic::PanicHookInfo<'_>) + Sync + Send + 'static>;

/// A panic hook that counts the panics (on any thread) and prints them: the code under test may
/// catch its panics and turn them into errors, so the hook is where they show. [`Panics::end`]
/// puts the previous hook back.
pub struct Panics {
    count: Arc<AtomicUsize>,
    previous: Hook,
}

impl Panics {
    pub fn count() -> Panics {
        let count = Arc::new(AtomicUsize::new(0));
        let counter = count.clone();
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            counter.fetch_add(1, Ordering::SeqCst);
            eprintln!("panic: {info}");
        }));
        Panics { count, previous }
    }

    /// The panics so far.
    pub fn so_far(&self) -> usize {
        self.count.load(Ordering::SeqCst)
    }

    pub fn end(self) {
        std::panic::set_hook(self.previous);
    }
}
