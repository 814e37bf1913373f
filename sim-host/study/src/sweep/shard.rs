//! `--shard I/N`: the I-th of N deterministic slices of a sweep's combination list.
//!
//! Shards are **1-based** (`1/4` .. `4/4`, as a cluster job array counts) and contiguous:
//! shard `I` of `N` runs combinations `floor((I-1) T / N) .. floor(I T / N)` of the `T`
//! combinations, so the shards' rows concatenated in shard order are exactly the unsharded
//! sweep's rows, and shard sizes differ by at most one.

use core::fmt;
use core::ops::Range;
use core::str::FromStr;

/// One slice of a sweep: shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ShardSpec {
    /// 1-based shard number, `1..=count`.
    pub index: usize,
    /// Number of shards, `>= 1`.
    pub count: usize,
}

/// Why a shard spec was refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShardSpecError {
    /// What the user wrote.
    pub spec: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl fmt::Display for ShardSpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "bad shard spec `{}`: {}; write I/N with 1 <= I <= N (1-based, e.g. 1/4 .. 4/4)",
            self.spec, self.reason
        )
    }
}

impl std::error::Error for ShardSpecError {}

impl ShardSpec {
    /// The whole sweep as one shard.
    pub const WHOLE: ShardSpec = ShardSpec { index: 1, count: 1 };

    /// Parse `I/N` (1-based).
    pub fn parse(spec: &str) -> Result<Self, ShardSpecError> {
        let err = |reason| ShardSpecError {
            spec: spec.to_string(),
            reason,
        };
        let (i, n) = spec.split_once('/').ok_or_else(|| err("no `/`"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| err("I is not a whole number"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| err("N is not a whole number"))?;
        if count == 0 {
            return Err(err("N must be at least 1"));
        }
        if index == 0 {
            return Err(err("shards are numbered from 1, so I must be at least 1"));
        }
        if index > count {
            return Err(err("I is larger than N"));
        }
        Ok(Self { index, count })
    }

    /// The combination indices this shard runs, out of `total`.
    pub fn slice(&self, total: usize) -> Range<usize> {
        let bound = |k: usize| {
            // u128 so that `k * total` cannot overflow for any usize inputs.
            (k as u128 * total as u128 / self.count as u128) as usize
        };
        bound(self.index - 1)..bound(self.index)
    }

    /// True for the trivial `1/1`.
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }
}

impl FromStr for ShardSpec {
    type Err = ShardSpecError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse(s)
    }
}

impl fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Value parser: a shard `I/N` (1-based), the refusal as text.
pub fn parse_shard(s: &str) -> Result<ShardSpec, String> {
    ShardSpec::parse(s).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn parses_one_based_specs() {
        assert_eq!(
            ShardSpec::parse("3/4").unwrap(),
            ShardSpec { index: 3, count: 4 }
        );
        assert_eq!(ShardSpec::parse("1/1").unwrap(), ShardSpec::WHOLE);
    }

    #[test]
    fn refuses_bad_specs() {
        for bad in ["0/4", "5/4", "1/0", "4", "a/b", "-1/4", "1/4/2", ""] {
            let e = ShardSpec::parse(bad).unwrap_err();
            assert!(e.to_string().contains(bad), "{e}");
        }
    }

    #[test]
    fn ten_in_four_shards() {
        let r: Vec<_> = (1..=4)
            .map(|i| ShardSpec { index: i, count: 4 }.slice(10))
            .collect();
        assert_eq!(r, vec![0..2, 2..5, 5..7, 7..10]);
    }

    proptest! {
        /// The shards of any sweep tile it exactly: contiguous, disjoint, in order, complete,
        /// sizes within one of each other.
        #[test]
        fn shards_tile_the_sweep(total in 0usize..10_000, count in 1usize..300) {
            let mut next = 0;
            let (mut smallest, mut largest) = (usize::MAX, 0);
            for index in 1..=count {
                let r = ShardSpec { index, count }.slice(total);
                prop_assert_eq!(r.start, next);
                prop_assert!(r.end >= r.start);
                smallest = smallest.min(r.len());
                largest = largest.max(r.len());
                next = r.end;
            }
            prop_assert_eq!(next, total);
            prop_assert!(largest - smallest <= 1);
        }
    }
}
