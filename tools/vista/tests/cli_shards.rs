//! `vista bake --shard I/N` and `--verify DIR` as a batch scheduler runs
//! them: shards baked at once into one folder equal a single-process bake
//! byte for byte; a killed shard resumes; a missing shard is named; `auto/N`
//! reads Slurm's and Kubernetes' index variables. No GPU.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

mod vista_cmd;

use vista_cmd::vista_cmd;

/// 4 096 m at 2 m, 5 LODs: 16 x 16 LOD-0 nodes, 341 in all; a shard of
/// two bakes for about a second on the 2-core CI machine, long enough to be
/// killed midway.
const WORLD: [&str; 6] = ["--extent", "4096", "--spacing", "2", "--lods", "5"];
const INDEX_VARS: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vista-cli-shards-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// `vista bake WORLD ARGS` with neither index variable set.
fn bake(args: &[&str]) -> Command {
    let mut c = vista_cmd();
    c.arg("bake").args(WORLD).args(args).arg("--no-progress");
    for v in INDEX_VARS {
        c.env_remove(v);
    }
    c
}

fn run(mut c: Command) -> (bool, String, String) {
    let out = c.output().expect("run vista");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn shard_cmd(dir: &Path, shard: &str) -> Command {
    bake(&["--out", dir.to_str().unwrap(), "--shard", shard])
}

/// Every node and error-tile file under `dir` (relative path, bytes);
/// manifests and vista's hidden temporaries aside.
fn products(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "vnode" || x == "verr") {
                out.push((p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

fn verify(dir: &Path) -> (bool, String, String) {
    run(bake(&["--verify", dir.to_str().unwrap()]))
}

fn temporaries(dir: &Path) -> usize {
    let mut n = 0;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            if e.path().is_dir() {
                stack.push(e.path());
            } else if e.file_name().to_string_lossy().contains(".vista-tmp-") {
                n += 1;
            }
        }
    }
    n
}

fn node_files(dir: &Path) -> usize {
    products(dir).iter().filter(|(p, _)| p.extension().is_some_and(|x| x == "vnode")).count()
}

#[test]
fn two_shards_at_once_equal_one_process_and_a_killed_shard_resumes() {
    let root = temp_dir("two");
    let (one, two) = (root.join("one"), root.join("two"));
    let (ok, _, err) = run(bake(&["--out", one.to_str().unwrap()]));
    assert!(ok, "{err}");
    assert_eq!(node_files(&one), 341);
    // Both shards at once into one folder.
    let a = shard_cmd(&two, "0/2").stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let (ok, _, err) = run(shard_cmd(&two, "1/2"));
    assert!(ok, "{err}");
    let a = a.wait_with_output().unwrap();
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    let expected = products(&one);
    assert!(products(&two) == expected, "two shards' files differ from one process's");
    let (ok, out, err) = verify(&two);
    assert!(ok, "{out}{err}");
    assert!(out.contains("341 of the plan's 341 nodes present and valid") && out.contains("2 of 2 complete"), "{out}");

    // Shard 1 killed once its first node file is on disk, then run again.
    let three = root.join("three");
    let (ok, _, err) = run(shard_cmd(&three, "0/2"));
    assert!(ok, "{err}");
    let before = node_files(&three);
    let mut b = shard_cmd(&three, "1/2").stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    // No time bound: the shard either writes a node or ends, and ending
    // first fails here.
    while node_files(&three) == before {
        assert!(b.try_wait().unwrap().is_none(), "shard 1 ended before writing a node");
        std::thread::sleep(Duration::from_millis(2));
    }
    b.kill().unwrap();
    let status = b.wait().unwrap();
    let partial = node_files(&three);
    assert!(!status.success() && partial < 341, "shard 1 finished ({partial} nodes) before it could be killed");
    let (ok, out, _) = verify(&three);
    assert!(!ok && out.contains("shard 1: no manifest"), "{out}");
    // A file the kill cut short stays a hidden temporary, which verify counts.
    let temps = temporaries(&three);
    if temps > 0 {
        assert!(out.contains(&format!("{temps} temporaries of killed writers")), "{temps} temporaries:\n{out}");
    }
    let (ok, out, err) = run(shard_cmd(&three, "1/2"));
    assert!(ok, "{err}");
    // What the killed run finished is kept, not baked again.
    let kept = partial - before;
    assert!(out.contains(&format!("{kept} reused")), "{kept} nodes were on disk:\n{out}");
    assert!(verify(&three).0);
    assert!(products(&three) == expected, "the resumed bake differs from one process's");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn verify_names_the_missing_shard() {
    let dir = temp_dir("missing");
    for shard in ["0/3", "2/3"] {
        let (ok, _, err) = run(shard_cmd(&dir, shard));
        assert!(ok, "{err}");
    }
    let (ok, out, err) = verify(&dir);
    assert!(!ok, "{out}");
    assert!(out.contains("1 of 3") || out.contains("2 of 3 complete"), "{out}");
    assert!(out.contains("shard 1: no manifest"), "{out}");
    assert!(!out.contains("shard 0:") && !out.contains("shard 2:"), "{out}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("rerun --shard 1/3"), "{err}");
    // A damaged node of a complete shard is named too.
    let (ok, _, err) = run(shard_cmd(&dir, "1/3"));
    assert!(ok, "{err}");
    assert!(verify(&dir).0);
    let victim = dir.join("lod0").join("0_0.vnode");
    let mut bytes = std::fs::read(&victim).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&victim, bytes).unwrap();
    let (ok, out, err) = verify(&dir);
    assert!(!ok && out.contains("lod0/0_0 corrupt") && err.contains("rerun --shard 0/3"), "{out}{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn auto_reads_the_schedulers_index() {
    for (var, index) in [("SLURM_ARRAY_TASK_ID", "2"), ("JOB_COMPLETION_INDEX", "1")] {
        let mut c = bake(&["--dry-run", "--shard", "auto/3"]);
        c.env(var, index);
        let (ok, out, err) = run(c);
        assert!(ok, "{var}: {err}");
        assert!(out.contains(&format!("shard {index} of 3 (0-based)")), "{var}: {out}");
    }
    let (ok, _, err) = run(bake(&["--dry-run", "--shard", "auto/3"]));
    assert!(!ok && err.trim_end().lines().count() == 1, "{err}");
    assert!(err.contains("SLURM_ARRAY_TASK_ID") && err.contains("JOB_COMPLETION_INDEX"), "{err}");
    // `all/N` lists every shard.
    let (ok, out, err) = run(bake(&["--dry-run", "--shard", "all/3"]));
    assert!(ok, "{err}");
    let table: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("shard  units"))
        .skip(1)
        .take_while(|l| !l.starts_with("spread:"))
        .collect();
    let first: Vec<&str> = table.iter().filter_map(|l| l.split_whitespace().next()).collect();
    assert_eq!(first, ["0", "1", "2"], "{out}");
}

/// The recipes in deploy/ run as written: their command line parses, and
/// their shard count matches the array's size (Slurm) or the completions
/// (Kubernetes).
#[test]
fn the_deploy_recipes_plan_their_shards() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let slurm = std::fs::read_to_string(here.join("deploy/slurm/bake-array.sh")).unwrap();
    let value = |prefix: &str| {
        let line = slurm.lines().find(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no {prefix} line"));
        line[prefix.len()..].trim_matches('"').to_string()
    };
    let last = value("#SBATCH --array=0-").parse::<u32>().unwrap();
    let world = value("WORLD=");
    let line = value("$VISTA bake ");
    let args: Vec<String> =
        line.replace("$WORLD", &world).split_whitespace().map(|a| a.replace("\"$OUT\"", "/nonexistent")).collect();
    assert!(args.contains(&format!("auto/{}", last + 1)), "{line}: not the array's {} shards", last + 1);
    let mut c = vista_cmd();
    c.arg("bake").args(&args).arg("--dry-run").env("SLURM_ARRAY_TASK_ID", last.to_string());
    c.env_remove("JOB_COMPLETION_INDEX");
    let (ok, out, err) = run(c);
    assert!(ok, "{args:?}: {err}");
    assert!(out.contains(&format!("shard {last} of {} (0-based)", last + 1)), "{out}");

    let job = std::fs::read_to_string(here.join("deploy/kubernetes/bake-job.yaml")).unwrap();
    let args_line = job.lines().find_map(|l| l.trim().strip_prefix("args: ")).expect("an args line");
    let args: Vec<String> = serde_json::from_str(args_line).expect("args as a flow sequence");
    let completions: u32 = job
        .lines()
        .find_map(|l| l.trim().strip_prefix("completions: "))
        .unwrap()
        .split('#')
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(args.contains(&format!("auto/{completions}")), "{args:?}: not the job's {completions} completions");
    let mut c = vista_cmd();
    c.args(&args).arg("--dry-run").env("JOB_COMPLETION_INDEX", "0").env_remove("SLURM_ARRAY_TASK_ID");
    let (ok, out, err) = run(c);
    assert!(ok, "{args:?}: {err}");
    assert!(out.contains(&format!("shard 0 of {completions} (0-based)")), "{out}");
}

/// A folder holds one sharded bake: a shard of another shard count or of
/// another world is refused before it writes anything (one line naming
/// both), also when two start at once (the claim is a hard link, so one of
/// them wins); a negative index gets the shard message, not the parser's.
#[test]
fn a_shard_refuses_a_folder_of_another_bake() {
    let root = temp_dir("foreign");
    let dir = root.join("bake");
    let (ok, _, err) = run(shard_cmd(&dir, "0/2"));
    assert!(ok, "{err}");
    let before = products(&dir);
    let refused = |mut c: Command, says: &[&str]| {
        let out = c.output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        for s in says {
            assert!(err.contains(s), "{s:?} missing: {err}");
        }
    };
    refused(shard_cmd(&dir, "1/3"), &["holds a bake of 2 shards of this world", "this one is 3 shards"]);
    let mut other = vista_cmd();
    other.args(["bake", "--extent", "2048", "--spacing", "2", "--lods", "4", "--no-progress", "--out"]);
    other.arg(&dir).args(["--shard", "1/2"]);
    refused(other, &["2 shards of a 4096 x 4096 m world", "this one is 2 shards of a 2048 x 2048 m world"]);
    // The same world from another source (a seed): the line names it.
    let mut seeded = shard_cmd(&dir, "1/2");
    seeded.args(["--seed", "7"]);
    refused(
        seeded,
        &["2 shards of this world with height source ", "this one is 2 shards of this world with height source "],
    );
    assert!(products(&dir) == before, "a refused shard wrote into the folder");
    refused(shard_cmd(&dir, "-1/2"), &["--shard \"-1/2\": the index must be 0 or more"]);

    // Two bakes starting at once into a fresh folder: exactly one goes on.
    let race = root.join("race");
    let a = shard_cmd(&race, "0/2").stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let (b_ok, _, b_err) = run(shard_cmd(&race, "0/3"));
    let a = a.wait_with_output().unwrap();
    assert!(
        a.status.success() != b_ok,
        "one of the two must be refused:\n{}\n{b_err}",
        String::from_utf8_lossy(&a.stderr)
    );

    // verify names the foreign shard count as a number, not Rust's Option.
    let m = std::fs::read_to_string(dir.join("manifest/shard-0-of-2.json")).unwrap();
    let m3 = m.replacen("\"shards\":2", "\"shards\":3", 1);
    std::fs::write(dir.join("manifest/shard-0-of-3.json"), m3).unwrap();
    let (_, out, _) = verify(&dir);
    assert!(out.contains("written for") && !out.contains("Some("), "{out}");
    let _ = std::fs::remove_dir_all(&root);
}
