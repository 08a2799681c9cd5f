//! `vista bake --shard I/N` (and `auto/N`, `all/N`) and `vista bake
//! --verify DIR`: a bake split for batch schedulers, and its check.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use vista::world::{verify, MissReason, NodeCache, ShardSplit, VerifyReport, WorldPlan};

use crate::world_args::LoadedWorld;
use crate::InputError;

/// Where `--shard auto/N` reads its index, in this order: a Slurm job
/// array's task id, a Kubernetes Indexed Job's completion index.
pub const INDEX_VARS: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

/// `--shard`'s value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardArg {
    Index {
        index: u32,
        count: u32,
    },
    /// The index from [`INDEX_VARS`].
    Auto {
        count: u32,
    },
    /// Every shard's plan (`--dry-run` only).
    All {
        count: u32,
    },
}

pub fn parse_shard(s: &str) -> Result<ShardArg, String> {
    let bad = || format!("--shard {s:?}: expected I/N (0-based index I of N shards), auto/N or all/N");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let count: u32 = n.trim().parse().map_err(|_| bad())?;
    if count == 0 {
        return Err(format!("--shard {s:?}: the shard count must be at least 1"));
    }
    match i.trim() {
        "auto" => Ok(ShardArg::Auto { count }),
        "all" => Ok(ShardArg::All { count }),
        i if i.starts_with('-') => {
            Err(format!("--shard {s:?}: the index must be 0 or more (0-based: 0 to {})", count - 1))
        }
        i => {
            let index: u32 = i.parse().map_err(|_| bad())?;
            if index >= count {
                return Err(format!(
                    "--shard {s:?}: the index must be below {count} (0-based, as Slurm's array task ids from 0 \
                     and Kubernetes' completion indexes are)"
                ));
            }
            Ok(ShardArg::Index { index, count })
        }
    }
}

impl ShardArg {
    pub fn count(self) -> u32 {
        match self {
            ShardArg::Index { count, .. } | ShardArg::Auto { count } | ShardArg::All { count } => count,
        }
    }

    /// The shard index (`None` for `all/N`); `auto/N` reads [`INDEX_VARS`].
    pub fn index(self) -> Result<Option<u32>> {
        match self {
            ShardArg::Index { index, .. } => Ok(Some(index)),
            ShardArg::All { .. } => Ok(None),
            ShardArg::Auto { count } => auto_index(count, |name| std::env::var(name).ok()).map(Some),
        }
    }
}

/// `auto/N`'s index from the scheduler's variables (`var` reads one).
fn auto_index(count: u32, var: impl Fn(&str) -> Option<String>) -> Result<u32> {
    let set: Vec<(&str, String)> = INDEX_VARS.iter().filter_map(|&n| var(n).map(|v| (n, v))).collect();
    let Some((name, value)) = set.first() else {
        let message = format!(
            "--shard auto/{count}: neither {} (a Slurm job array) nor {} (a Kubernetes Indexed Job) is set; give the \
             index instead: --shard I/{count}",
            INDEX_VARS[0], INDEX_VARS[1]
        );
        return Err(InputError(message).into());
    };
    if let Some((other, v)) = set.get(1).filter(|(_, v)| v.trim() != value.trim()) {
        let message = format!("--shard auto/{count}: {name}={value} and {other}={v} disagree; give --shard I/{count}");
        return Err(InputError(message).into());
    }
    let index: u32 = value
        .trim()
        .parse()
        .map_err(|_| InputError(format!("--shard auto/{count}: {name}={value:?} is not a shard index")))?;
    if index >= count {
        let message = format!(
            "--shard auto/{count}: {name}={index} is not below {count}; number the tasks from 0 (Slurm: --array=0-{})",
            count - 1
        );
        return Err(InputError(message).into());
    }
    Ok(index)
}

/// The split of the world into `count` shards, as the user's input error.
pub fn split(world: &vista::world::WorldDesc, count: u32) -> Result<ShardSplit> {
    ShardSplit::new(world, count).map_err(|e| InputError(e.to_string()).into())
}

/// `--dry-run --shard`: one shard's plan, or every shard's as a table.
pub fn write_plans(out: &mut String, split: &ShardSplit, index: Option<u32>, plan: &WorldPlan) -> Result<()> {
    writeln!(
        out,
        "shards:   {} of the whole world, split at LOD {} (units: that level's cells with everything under them, \
         weighed by the built-in per-node and per-sample estimates)",
        split.count(),
        split.split_lod()
    )?;
    if let Some(i) = index {
        writeln!(out, "{}", split.shard_plan(i, plan))?;
        return Ok(());
    }
    let threads = plan.threads;
    writeln!(
        out,
        "          tiles: error tiles a shard makes, of the roots it owns + of its units in roots other shards own"
    )?;
    writeln!(
        out,
        "{:>6} {:>6} {:>10} {:>10} {:>11} {:>13} {:>13}",
        "shard",
        "units",
        "nodes",
        "LOD 0",
        "disk",
        "tiles",
        format!("time/{threads}thr")
    )?;
    let shards: Vec<_> = (0..split.count()).map(|i| split.shard_plan(i, plan)).collect();
    for s in &shards {
        let roots = format!("{} + {}", s.roots, s.unit_tiles);
        writeln!(
            out,
            "{:>6} {:>6} {:>10} {:>10} {:>11} {:>13} {:>13}",
            s.index,
            s.units,
            s.nodes(),
            s.nodes_per_lod[0],
            vista::world::human_bytes(s.disk_bytes as f64),
            roots,
            hours(s.seconds())
        )?;
    }
    let secs: Vec<f64> = shards.iter().map(|s| s.seconds()).collect();
    let (lo, hi) = secs.iter().fold((f64::MAX, 0f64), |(lo, hi), &s| (lo.min(s), hi.max(s)));
    let total: f64 = shards.iter().map(|s| s.thread_seconds()).sum();
    writeln!(
        out,
        "spread:   the slowest shard's estimate is {:.3} x the fastest's; all shards {} of thread time ({:.1} % more \
         than one process: the units' tiles in roots other shards own)",
        hi / lo.max(1e-9),
        hours(total),
        100.0 * (total / (plan.bake_seconds() * threads as f64) - 1.0)
    )?;
    Ok(())
}

/// Hours with two decimals from an hour up (a continent's shards), else
/// minutes or seconds.
fn hours(s: f64) -> String {
    match s {
        s if s >= 36.0 * 100.0 => format!("{:.2} h", s / 3600.0),
        s if s >= 90.0 => format!("{:.1} min", s / 60.0),
        s => format!("{s:.1} s"),
    }
}

/// `vista bake --verify DIR`.
pub fn run_verify(w: &LoadedWorld, dir: &Path) -> Result<()> {
    if !dir.is_dir() {
        return Err(InputError(format!("--verify {}: no such folder", dir.display())).into());
    }
    let cache = NodeCache::with_settings(dir, w.desc, w.source.clone(), w.holes.clone(), w.bake.clone())?;
    let report = verify(&cache, dir)?;
    let mut out = String::new();
    write_report(&mut out, dir, &report)?;
    crate::bake::emit(&out)?;
    if report.is_complete() {
        return Ok(());
    }
    let shards = report.incomplete_shards();
    let what = match (report.shards, shards.is_empty()) {
        _ if report.valid == 0 && report.stale > 0 => {
            "its files are of another world or settings: give --verify the world and options of the bake".to_string()
        }
        (Some(n), false) => {
            let list: Vec<String> = shards.iter().map(|i| format!("--shard {i}/{n}")).collect();
            format!("rerun {} (the same world and options; valid nodes are kept)", list.join(", "))
        }
        _ => "bake it again into the same folder (valid nodes are kept)".to_string(),
    };
    anyhow::bail!("the bake in {} is incomplete: {what}", dir.display())
}

fn write_report(out: &mut String, dir: &Path, r: &VerifyReport) -> Result<()> {
    writeln!(
        out,
        "verify:   {}: {} of the plan's {} nodes present and valid ({} missing, {} corrupt, {} of another world or \
         settings); {:.1} s",
        dir.display(),
        r.valid,
        r.nodes,
        r.missing,
        r.corrupt,
        r.stale,
        r.seconds
    )?;
    match r.shards {
        None => writeln!(out, "shards:   no manifest of this bake in {}", dir.join("manifest").display())?,
        Some(n) => {
            let done = r.verdicts.iter().filter(|v| v.is_complete()).count();
            writeln!(out, "shards:   {done} of {n} complete (manifest written, every node valid and unchanged)")?;
        }
    }
    for v in r.verdicts.iter().filter(|v| !v.is_complete()) {
        let manifest = if v.has_manifest { "manifest written" } else { "no manifest" };
        let examples: Vec<String> = v.examples.iter().map(|(id, why)| format!("{id} {}", reason(*why))).collect();
        write!(out, "  shard {}: {manifest}; {} of its {} nodes missing or invalid", v.shard, v.bad, v.nodes)?;
        if v.changed > 0 {
            write!(out, "; {} files changed since its manifest", v.changed)?;
        }
        if !examples.is_empty() {
            write!(out, " (e.g. {})", examples.join(", "))?;
        }
        writeln!(out)?;
    }
    if let Some(first) = r.temporaries.first() {
        writeln!(
            out,
            "  {} temporaries of killed writers (e.g. {}): harmless; delete them when no bake writes here",
            r.temporaries.len(),
            first.display()
        )?;
    }
    for f in &r.foreign {
        writeln!(out, "  ignored {}: {}", f.path.display(), f.why)?;
    }
    Ok(())
}

fn reason(r: MissReason) -> &'static str {
    match r {
        MissReason::Missing => "missing",
        MissReason::Corrupt => "corrupt",
        MissReason::Stale => "stale",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shard_option_parses_index_auto_and_all() {
        assert_eq!(parse_shard("3/8"), Ok(ShardArg::Index { index: 3, count: 8 }));
        assert_eq!(parse_shard("auto/64"), Ok(ShardArg::Auto { count: 64 }));
        assert_eq!(parse_shard("all/7"), Ok(ShardArg::All { count: 7 }));
        for bad in ["8/8", "1/0", "x/2", "3", "-1/4", "1/2/3", ""] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn auto_reads_slurm_then_kubernetes() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |n: &str| pairs.iter().find(|p| p.0 == n).map(|p| p.1.to_string())
        };
        assert_eq!(auto_index(4, env(&[("SLURM_ARRAY_TASK_ID", "2")])).unwrap(), 2);
        assert_eq!(auto_index(4, env(&[("JOB_COMPLETION_INDEX", "3")])).unwrap(), 3);
        assert_eq!(auto_index(4, env(&[("SLURM_ARRAY_TASK_ID", "1"), ("JOB_COMPLETION_INDEX", "1")])).unwrap(), 1);
        for (pairs, says) in [
            (&[][..], "neither"),
            (&[("SLURM_ARRAY_TASK_ID", "1"), ("JOB_COMPLETION_INDEX", "2")][..], "disagree"),
            (&[("SLURM_ARRAY_TASK_ID", "4")][..], "--array=0-3"),
            (&[("JOB_COMPLETION_INDEX", "one")][..], "not a shard index"),
        ] {
            let e = auto_index(4, env(pairs)).unwrap_err().to_string();
            assert!(e.contains(says) && e.lines().count() == 1, "{e}");
        }
    }
}
