//! The sweep metadata reader (`SweepMeta::parse`, each shard's `sweep.toml`) and the merge's
//! checks on it (`merge::merge_shards`, `sandjumper merge`) on any text: they never panic and
//! never run away with memory or time, whatever the shard counts and spec lists claim; a
//! merge they accept is one whole sweep (shard 1/1) of the combinations its spec expands to.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_study::sweep::SweepMeta;
use sandjumper_study::sweep::merge::{ShardDir, merge_shards, spec_of};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(meta) = SweepMeta::parse(text) else {
        return;
    };
    let _ = spec_of(&meta);
    let shard = ShardDir {
        dir: "shard-1".into(),
        meta,
        outcome: Default::default(),
    };
    if let Ok((merged, outcome)) = merge_shards(vec![shard]) {
        assert_eq!((merged.shard.index, merged.shard.count), (1, 1));
        assert_eq!(merged.shard.first, 0);
        assert_eq!(merged.shard.end, merged.total_combinations);
        assert_eq!(
            outcome.rows.len() + outcome.failures.len(),
            merged.total_combinations
        );
    }
});
