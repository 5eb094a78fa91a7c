//! Shards: disjoint parts of one piece of work that separate processes (or a scheduler's
//! array tasks) run apart and `ppm merge` joins ([`crate::merge`]).
//!
//! A path-traced reference splits by rows: shard `I/N` renders every row `y` with
//! `y % N == I`, each pixel with exactly the samples (and the sums, in the same order) it has
//! in one run of the whole image, so the merge of the N shards is that run, bit for bit. A
//! progressive `sppm` render cannot split its iterations that way (every iteration reads the
//! statistics the last one left), so its shards are independent runs with their own seeds,
//! averaged by their iteration counts.

use serde::{Deserialize, Serialize};

/// Part `index` of `count` (0-based, as Slurm's `SLURM_ARRAY_TASK_ID` and Kubernetes'
/// `JOB_COMPLETION_INDEX` count).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which part, `0..count`.
    pub index: u32,
    /// How many parts.
    pub count: u32,
}

impl Shard {
    /// The whole work, in one part.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (`0 <= I < N`); errors say what is wrong with the text.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = |why: &str| format!("\"{text}\": {why} (give I/N with 0 <= I < N, e.g. 2/4)");
        let (i, n) = text.split_once('/').ok_or_else(|| bad("no '/'"))?;
        let index: u32 = i
            .trim()
            .parse()
            .map_err(|_| bad("I is not a whole number"))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if count == 0 {
            return Err(bad("N must be at least 1"));
        }
        if index >= count {
            return Err(bad("I must be below N"));
        }
        Ok(Self { index, count })
    }

    /// Whether this shard renders row `y` of a reference.
    pub fn owns_row(&self, y: u32) -> bool {
        y % self.count == self.index
    }

    /// Whether this is the whole work.
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }

    /// The seed of this shard's independent `sppm` run: `seed` itself for shard 0, others
    /// apart from it by the golden-ratio increment (the generator hashes its keys, so any
    /// distinct seeds give independent streams).
    pub fn seed(&self, seed: u32) -> u32 {
        seed.wrapping_add(self.index.wrapping_mul(0x9e37_79b9))
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_split_rows_without_overlap() {
        assert_eq!(Shard::parse("2/4"), Ok(Shard { index: 2, count: 4 }));
        for bad in ["4/4", "1/0", "x/2", "3", "-1/2", "1/2/3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        let shards: Vec<Shard> = (0..3).map(|i| Shard { index: i, count: 3 }).collect();
        for y in 0..10 {
            assert_eq!(shards.iter().filter(|s| s.owns_row(y)).count(), 1);
        }
        assert_eq!(shards[0].seed(7), 7);
        assert_ne!(shards[1].seed(7), shards[2].seed(7));
    }
}
