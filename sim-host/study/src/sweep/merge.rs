//! Joining the shard directories of one sweep into the whole sweep.
//!
//! Refuses, with a message naming the directories: a directory that is not a sweep, shards
//! of different sweeps (spec hash) or shard counts, the same shard twice (overlap), missing
//! shards, and a shard whose rows do not match the combinations it should hold.

use std::fmt;
use std::path::{Path, PathBuf};

use sandjumper_model::params::ModelName;

use super::SweepDrive;
use super::{
    Combination, ShardMeta, ShardSpec, SweepFailure, SweepMeta, SweepOutcome, SweepRow, SweepSpec,
    files, read_csv,
};
use sandjumper_model::trajectory::{kind_name, parse_kind};

/// Why shards could not be merged.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MergeError(pub String);

impl fmt::Display for MergeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MergeError {}

/// One shard directory, read.
#[derive(Clone, Debug, PartialEq)]
pub struct ShardDir {
    /// Where it was read from.
    pub dir: PathBuf,
    /// Its `sweep.toml`.
    pub meta: SweepMeta,
    /// Its rows and failures.
    pub outcome: SweepOutcome,
}

/// Read `sweep.toml`, `sweep.csv` and `failures.csv` of a sweep directory.
pub fn read_sweep_dir(dir: &Path) -> Result<ShardDir, MergeError> {
    let meta_path = dir.join(files::META);
    let text = std::fs::read_to_string(&meta_path).map_err(|e| {
        MergeError(format!(
            "`{}` is not a sweep directory: cannot read {}: {e}",
            dir.display(),
            files::META
        ))
    })?;
    let meta = SweepMeta::parse(&text)
        .map_err(|e| MergeError(format!("`{}`: {e}", meta_path.display())))?;
    let rows = read_csv::<SweepRow>(&dir.join(files::ROWS)).map_err(MergeError)?;
    let failures = read_csv::<SweepFailure>(&dir.join(files::FAILURES)).map_err(MergeError)?;
    Ok(ShardDir {
        dir: dir.to_path_buf(),
        meta,
        outcome: SweepOutcome { rows, failures },
    })
}

/// Rebuild the sweep spec from its metadata.
pub fn spec_of(meta: &SweepMeta) -> Result<SweepSpec, MergeError> {
    let kinds = meta
        .spec
        .kinds
        .iter()
        .map(|k| parse_kind(k).ok_or_else(|| MergeError(format!("unknown jump kind `{k}`"))))
        .collect::<Result<_, _>>()?;
    let models = meta
        .spec
        .models
        .iter()
        .map(|m| {
            m.parse::<ModelName>()
                .map_err(|_| MergeError(format!("unknown model `{m}`")))
        })
        .collect::<Result<_, _>>()?;
    Ok(SweepSpec {
        kinds,
        models,
        phis: meta.spec.phi.clone(),
        freqs_hz: meta.spec.freq_hz.clone(),
        taus_s: meta.spec.tau_s.clone(),
        rtol: meta.spec.rtol,
        drive: SweepDrive::parse(&meta.spec.drive)
            .ok_or_else(|| MergeError(format!("unknown drive `{}`", meta.spec.drive)))?,
    })
}

fn same_combination(c: &Combination, kind: &str, model: &str, phi: f64, f: f64, tau: f64) -> bool {
    kind_name(c.kind) == kind
        && c.model.as_str() == model
        && c.phi == phi
        && c.freq_hz == f
        && c.tau_s == tau
}

/// Check that a shard holds `expected` rows and failures, as many as its `sweep.toml` says.
fn check_counts(shard: &ShardDir, expected: usize) -> Result<(), MergeError> {
    let rows = &shard.outcome.rows;
    let fails = &shard.outcome.failures;
    if rows.len() + fails.len() != expected
        || rows.len() != shard.meta.shard.rows
        || fails.len() != shard.meta.shard.failures
    {
        return Err(MergeError(format!(
            "shard {}/{} in `{}` is incomplete or altered: {} rows + {} failures on disk, \
             {} + {} recorded in {}, {} combinations expected",
            shard.meta.shard.index,
            shard.meta.shard.count,
            shard.dir.display(),
            rows.len(),
            fails.len(),
            shard.meta.shard.rows,
            shard.meta.shard.failures,
            files::META,
            expected
        )));
    }
    Ok(())
}

/// Check that a shard's rows and failures are the combinations `expected`, in order; its
/// counts are [`check_counts`]'s, checked before the spec was expanded.
fn check_order(shard: &ShardDir, expected: &[Combination]) -> Result<(), MergeError> {
    let rows = &shard.outcome.rows;
    let fails = &shard.outcome.failures;
    let (mut r, mut f) = (0, 0);
    for (i, c) in expected.iter().enumerate() {
        if r < rows.len() {
            let x = &rows[r];
            if same_combination(c, &x.kind, &x.model, x.phi, x.freq_hz, x.tau_s) {
                r += 1;
                continue;
            }
        }
        if f < fails.len() {
            let x = &fails[f];
            if same_combination(c, &x.kind, &x.model, x.phi, x.freq_hz, x.tau_s) {
                f += 1;
                continue;
            }
        }
        return Err(MergeError(format!(
            "shard {}/{} in `{}`: combination {} ({} {} phi={} f={} Hz tau={} s) is missing or out of order",
            shard.meta.shard.index,
            shard.meta.shard.count,
            shard.dir.display(),
            shard.meta.shard.first + i,
            kind_name(c.kind),
            c.model,
            c.phi,
            c.freq_hz,
            c.tau_s
        )));
    }
    Ok(())
}

/// Merge shard directories (any order) into the whole sweep. Returns the merged metadata
/// (shard `1/1`) and the rows and failures in sweep order.
pub fn merge_shards(mut shards: Vec<ShardDir>) -> Result<(SweepMeta, SweepOutcome), MergeError> {
    let Some(first) = shards.first().cloned() else {
        return Err(MergeError("no shard directories given".into()));
    };
    for s in &shards[1..] {
        if s.meta.spec_hash != first.meta.spec_hash
            || s.meta.total_combinations != first.meta.total_combinations
        {
            return Err(MergeError(format!(
                "`{}` and `{}` are shards of different sweeps (spec hash {} vs {}): \
                 only shards of one sweep command can be merged",
                first.dir.display(),
                s.dir.display(),
                first.meta.spec_hash,
                s.meta.spec_hash
            )));
        }
        if s.meta.shard.count != first.meta.shard.count {
            return Err(MergeError(format!(
                "`{}` is one of {} shards but `{}` is one of {}: all shards must use the same N",
                first.dir.display(),
                first.meta.shard.count,
                s.dir.display(),
                s.meta.shard.count
            )));
        }
    }
    shards.sort_by_key(|s| s.meta.shard.index);
    let count = first.meta.shard.count;
    for w in shards.windows(2) {
        if w[0].meta.shard.index == w[1].meta.shard.index {
            return Err(MergeError(format!(
                "shard {}/{count} given twice (overlap): `{}` and `{}`",
                w[0].meta.shard.index,
                w[0].dir.display(),
                w[1].dir.display()
            )));
        }
    }
    // Shards are sorted and distinct: all are there when they are 1..=count. Only the first
    // few missing are named (a damaged count could be huge).
    if shards.len() != count
        || shards
            .iter()
            .enumerate()
            .any(|(k, s)| s.meta.shard.index != k + 1)
    {
        let missing: Vec<String> = (1..=count)
            .filter(|i| !shards.iter().any(|s| s.meta.shard.index == *i))
            .take(10)
            .map(|i| format!("{i}/{count}"))
            .collect();
        let more = count
            .saturating_sub(shards.len())
            .saturating_sub(missing.len());
        return Err(MergeError(format!(
            "missing shard(s) {}{}: give every shard 1/{count} .. {count}/{count} of the sweep",
            missing.join(", "),
            if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            }
        )));
    }
    let spec = spec_of(&first.meta)?;
    // Counted before it is expanded: a damaged spec cannot make the merge run out of memory.
    let total = spec.count().unwrap_or(usize::MAX);
    if total != first.meta.total_combinations {
        return Err(MergeError(format!(
            "`{}`: {} records {} combinations but its spec expands to {total}",
            first.dir.display(),
            files::META,
            first.meta.total_combinations
        )));
    }
    let slice_of = |s: &ShardDir| {
        ShardSpec {
            index: s.meta.shard.index,
            count,
        }
        .slice(total)
    };
    for s in &shards {
        let slice = slice_of(s);
        if s.meta.shard.first != slice.start || s.meta.shard.end != slice.end {
            return Err(MergeError(format!(
                "shard {}/{count} in `{}` covers combinations {}..{}, expected {}..{}",
                s.meta.shard.index,
                s.dir.display(),
                s.meta.shard.first,
                s.meta.shard.end,
                slice.start,
                slice.end
            )));
        }
        check_counts(s, slice.len())?;
    }
    // Each shard holds its slice's count: the expansion is no larger than what was read.
    let combos = spec.combinations();
    let mut outcome = SweepOutcome::default();
    for s in shards {
        check_order(&s, &combos[slice_of(&s)])?;
        outcome.rows.extend(s.outcome.rows);
        outcome.failures.extend(s.outcome.failures);
    }
    let meta = SweepMeta {
        shard: ShardMeta {
            index: 1,
            count: 1,
            first: 0,
            end: total,
            rows: outcome.rows.len(),
            failures: outcome.failures.len(),
        },
        ..first.meta
    };
    Ok((meta, outcome))
}

#[cfg(test)]
mod tests {
    use super::{MergeError, ShardDir, merge_shards};
    use crate::sweep::SweepMeta;

    /// One shard of `sweep.toml` text with no rows, merged.
    fn merge_alone(text: &str) -> MergeError {
        let meta = SweepMeta::parse(text).expect("a sweep.toml");
        let shard = ShardDir {
            dir: "shard".into(),
            meta,
            outcome: Default::default(),
        };
        merge_shards(vec![shard]).expect_err("refused")
    }

    /// A damaged shard count (10^15) is refused naming ten missing shards and counting the
    /// rest, where the list of every missing shard once ran out of memory.
    #[test]
    fn a_huge_shard_count_is_refused_without_listing_every_shard() {
        let e = merge_alone(include_str!("../../fuzz/corpus/sweep_merge/huge-count"));
        assert!(e.0.contains("missing shard(s) 1/1000000000000000"), "{e}");
        assert!(e.0.contains("and 999999999999989 more"), "{e}");
    }

    /// A spec of 217 million combinations (216,720,000) whose shard holds none is refused before it is
    /// expanded (8.7 GB of combinations): the shard's count is checked first.
    #[test]
    fn a_huge_spec_is_refused_before_it_is_expanded() {
        let e = merge_alone(include_str!("../../fuzz/corpus/sweep_merge/huge-spec"));
        assert!(e.0.contains("incomplete or altered"), "{e}");
        assert!(e.0.contains("216720000 combinations expected"), "{e}");
    }
}
