//! `faceanim batch` as a studio runs it: a manifest of speech lines (flite's voices, made here
//! by tools/batch_lines.py, some rows broken on purpose) run with `--jobs 2`, then again, then
//! with a transcript changed and a take edited; the worker contract as Kubernetes' Indexed Job
//! (deploy/kubernetes) runs it; and the Ray driver (deploy/ray) on a real two-node Ray cluster
//! on this machine, with a worker killed mid-run.
//!
//! CI makes 40 lines (and 16 for Ray); `FACEANIM_BATCH_LINES` asks for more (the benchmark,
//! scripts/bench-batch.py, runs 1,000).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use faceanim_batch::EXIT_BAD_INPUT;

/// A batch of `lines` speech lines with `broken` rows broken, made in a fresh folder under
/// test-output/; the folder and what batch_lines.py says of the rows.
fn lines(test: &str, lines: usize, broken: usize) -> (PathBuf, serde_json::Value) {
    let dir = support::fresh_output_dir(test);
    let made = support::succeeded(
        "tools/batch_lines.py",
        Command::new("python3")
            .arg(support::repo().join("tools/batch_lines.py"))
            .arg(&dir)
            .args([
                "--lines",
                &lines.to_string(),
                "--broken",
                &broken.to_string(),
            ])
            .output()
            .unwrap(),
    );
    (dir, serde_json::from_slice(&made.stdout).unwrap())
}

fn count() -> usize {
    std::env::var("FACEANIM_BATCH_LINES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(40)
}

/// Runs `faceanim batch` in `dir` with `args` and `env`.
fn batch(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_faceanim"));
    command.current_dir(dir).arg("batch").args(args);
    for name in faceanim_batch::select::INDEX_VARIABLES {
        command.env_remove(name);
    }
    command.envs(env.iter().copied());
    command.output().unwrap()
}

/// The `row` events of a `--progress json` run, by row id.
fn row_events(out: &Output) -> BTreeMap<String, Vec<serde_json::Value>> {
    let mut rows: BTreeMap<String, Vec<serde_json::Value>> = BTreeMap::new();
    for line in String::from_utf8_lossy(&out.stderr).lines() {
        let Ok(event) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if event["event"] == "row" {
            rows.entry(event["id"].as_str().unwrap().to_owned())
                .or_default()
                .push(event);
        }
    }
    rows
}

/// Checks that `out` ended with `code`, showing its messages otherwise.
fn assert_exit(out: &Output, code: u8, what: &str) {
    assert_eq!(
        out.status.code(),
        Some(i32::from(code)),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every row's single status in `out`.
fn statuses(out: &Output) -> BTreeMap<String, String> {
    row_events(out)
        .into_iter()
        .map(|(id, events)| {
            assert_eq!(events.len(), 1, "{id} reported {} times", events.len());
            (id, events[0]["status"].as_str().unwrap().to_owned())
        })
        .collect()
}

/// The ids of the rows made good, and of those broken.
fn good_and_broken(made: &serde_json::Value) -> (Vec<String>, Vec<String>) {
    let rows = made["rows"].as_array().unwrap();
    let ids = |broken: bool| {
        rows.iter()
            .filter(|r| r["broken"].is_null() != broken)
            .map(|r| r["id"].as_str().unwrap().to_owned())
            .collect()
    };
    (ids(false), ids(true))
}

/// The index of the row `id`, as a worker is given it.
fn index_of(made: &serde_json::Value, id: &str) -> String {
    made["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == id)
        .unwrap()["index"]
        .to_string()
}

/// The modification time of every file under `dir/out`, by name.
fn written(dir: &Path) -> BTreeMap<String, std::time::SystemTime> {
    std::fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap())
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                e.metadata().unwrap().modified().unwrap(),
            )
        })
        .collect()
}

/// Checks every good row's take: a clip of the line's length whose mouth opens.
fn assert_takes(dir: &Path, good: &[String]) {
    for id in good {
        let clip: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join(format!("out/{id}.json"))).unwrap())
                .unwrap();
        let jaw = support::column(&clip, "jawOpen");
        assert!(jaw.len() > 30, "{id}: {} frames", jaw.len());
        let open = jaw.iter().copied().fold(0.0, f64::max);
        assert!(open > 0.1, "{id}: the mouth never opens ({open})");
        assert!(
            dir.join(format!("out/{id}.json.made.json")).is_file(),
            "{id} has no record"
        );
    }
    for entry in std::fs::read_dir(dir.join("out")).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            !name.starts_with(faceanim_batch::record::STAGED_PREFIX),
            "a staged output was left behind: {name}"
        );
    }
}

#[test]
fn a_manifest_of_lines_runs_each_once_keeps_edits_and_redoes_only_what_changed() {
    let (dir, made) = lines("batch-jobs", count(), 5);
    let (good, broken) = good_and_broken(&made);
    assert_eq!(broken.len(), 5);

    // First run: every good line done once, every broken one reported as bad input.
    let first = batch(
        &dir,
        &["lines.jsonl", "--jobs", "2", "--progress", "json"],
        &[],
    );
    assert_exit(&first, EXIT_BAD_INPUT, "the first run");
    let status = statuses(&first);
    assert_eq!(status.len(), good.len() + broken.len());
    for id in &good {
        assert_eq!(status[id], "done", "{id}");
    }
    let events = row_events(&first);
    for id in &broken {
        assert_eq!(status[id], "bad_input", "{id}");
        let event = &events[id][0];
        assert!(event["attempts"].as_u64().unwrap() <= 1, "{id} was retried");
        assert!(!dir.join(format!("out/{id}.json")).exists());
    }
    // Each broken row is named with what is wrong.
    let errors: Vec<String> = broken
        .iter()
        .map(|id| events[id][0]["error"].as_str().unwrap().to_owned())
        .collect();
    for words in [
        "field `speech`",
        "ffmpeg",
        "no sound",
        "frames-per-second",
        "field `transcript`",
    ] {
        assert!(
            errors.iter().any(|e| e.contains(words)),
            "no row says {words:?}: {errors:#?}"
        );
    }
    assert_takes(&dir, &good);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("lines.jsonl.report.json")).unwrap())
            .unwrap();
    assert_eq!(report["counts"]["done"], good.len());
    assert_eq!(report["counts"]["bad_input"], broken.len());
    let summary = String::from_utf8_lossy(&first.stdout);
    assert!(
        summary.contains(&format!("{} done", good.len())),
        "{summary}"
    );

    // Second run: nothing changed, nothing written.
    let before = written(&dir);
    let second = batch(
        &dir,
        &["lines.jsonl", "--jobs", "2", "--progress", "json"],
        &[],
    );
    assert_eq!(second.status.code(), Some(i32::from(EXIT_BAD_INPUT)));
    let status = statuses(&second);
    for id in &good {
        assert_eq!(status[id], "skipped", "{id}");
    }
    // A broken row is reported again, from its record, without being started.
    let events = row_events(&second);
    for id in &broken {
        assert_eq!(status[id], "bad_input", "{id}");
        assert_eq!(events[id][0]["attempts"], 0, "{id} was started again");
    }
    assert_eq!(written(&dir), before, "a second run wrote files");

    // A changed transcript redoes its line only; an edited take is left alone even though its
    // speech changed.
    let rows = made["rows"].as_array().unwrap();
    let from_file = rows
        .iter()
        .find(|r| r["broken"].is_null() && r["index"].as_u64().unwrap() % 10 == 3)
        .unwrap()["id"]
        .as_str()
        .unwrap()
        .to_owned();
    std::fs::write(
        dir.join(format!("text/{from_file}.txt")),
        "Bob bought a map of the bay.\n",
    )
    .unwrap();
    let edited = good.iter().find(|id| **id != from_file).unwrap().clone();
    let take = dir.join(format!("out/{edited}.json"));
    let mut clip: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&take).unwrap()).unwrap();
    clip["name"] = "polished in the studio".into();
    let edit = serde_json::to_vec(&clip).unwrap();
    std::fs::write(&take, &edit).unwrap();
    // The line delivered again, by another voice.
    let words = rows.iter().find(|r| r["id"] == edited.as_str()).unwrap()["words"]
        .as_str()
        .unwrap();
    support::flite("kal16", words, &dir.join(format!("audio/{edited}.wav")));
    let third = batch(
        &dir,
        &["lines.jsonl", "--jobs", "2", "--progress", "json"],
        &[],
    );
    let status = statuses(&third);
    for id in &good {
        let expected = if *id == from_file {
            "done"
        } else if *id == edited {
            "edited"
        } else {
            "skipped"
        };
        assert_eq!(status[id], expected, "{id}");
    }
    assert_eq!(
        std::fs::read(&take).unwrap(),
        edit,
        "the edited take was overwritten"
    );
    // Asked to, the batch overwrites it.
    let fourth = batch(
        &dir,
        &[
            "lines.jsonl",
            "--index",
            &index_of(&made, &edited),
            "--overwrite-edits",
            "--progress",
            "json",
        ],
        &[],
    );
    assert_eq!(fourth.status.code(), Some(0));
    assert_eq!(statuses(&fourth)[&edited], "done");
    assert_ne!(std::fs::read(&take).unwrap(), edit);
}

/// The Kubernetes Job in deploy/kubernetes, read as Kubernetes reads it.
fn job_manifest() -> serde_json::Value {
    let out = support::succeeded(
        "reading the Job's YAML",
        Command::new("python3")
            .args([
                "-c",
                "import json, sys, yaml; print(json.dumps(yaml.safe_load(open(sys.argv[1]))))",
            ])
            .arg(support::repo().join("deploy/kubernetes/faceanim-batch-job.yaml"))
            .output()
            .unwrap(),
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn the_kubernetes_job_runs_the_worker_contract_by_its_completion_index() {
    let (dir, made) = lines("batch-indexed", 12, 2);
    let (good, broken) = good_and_broken(&made);
    let job = job_manifest();
    let spec = &job["spec"];
    assert_eq!(spec["completionMode"], "Indexed");
    let container = &spec["template"]["spec"]["containers"][0];
    let rules = spec["podFailurePolicy"]["rules"].as_array().unwrap();
    let fail_index = rules.iter().find(|r| r["action"] == "FailIndex").unwrap();
    // The exit status the Job does not retry is the one the worker gives bad input.
    assert_eq!(
        fail_index["onExitCodes"]["values"],
        serde_json::json!([EXIT_BAD_INPUT])
    );
    assert_eq!(
        fail_index["onExitCodes"]["containerName"],
        container["name"]
    );
    assert!(spec["backoffLimitPerIndex"].as_u64().unwrap() > 0);
    // The container's arguments, with the shared volume here, for each index Kubernetes gives.
    let args: Vec<String> = container["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            a.as_str()
                .unwrap()
                .replace("/data/", &format!("{}/", dir.display()))
        })
        .collect();
    assert_eq!(args[0], "batch");
    let args: Vec<&str> = args[1..].iter().map(String::as_str).collect();
    let rows = made["rows"].as_array().unwrap();
    for (k, row) in rows.iter().enumerate() {
        let index = k.to_string();
        let out = batch(&dir, &args, &[("JOB_COMPLETION_INDEX", &index)]);
        let expected = if row["broken"].is_null() {
            0
        } else {
            EXIT_BAD_INPUT
        };
        assert_exit(&out, expected, &format!("index {k}"));
        // One row per pod: its own, and only its own.
        let status = statuses(&out);
        assert_eq!(
            status.keys().collect::<Vec<_>>(),
            [row["id"].as_str().unwrap()]
        );
    }
    assert_takes(&dir, &good);
    // A pod started again for a row already done (a retry after its node was lost) finds it done.
    let again = batch(&dir, &args, &[("JOB_COMPLETION_INDEX", "0")]);
    assert_eq!(again.status.code(), Some(0));
    assert_eq!(statuses(&again)[good[0].as_str()], "skipped");
    // An index past the rows, and an index that is no number, are the Job's mistakes: 42.
    for bad in [rows.len().to_string(), "x".to_owned()] {
        let out = batch(&dir, &args, &[("JOB_COMPLETION_INDEX", &bad)]);
        assert_exit(&out, EXIT_BAD_INPUT, &format!("index {bad}"));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.starts_with("error: ") && !stderr.contains("panicked"),
            "{stderr}"
        );
    }
    // The other engines' variables, and a shard, pick the same rows.
    let slurm = batch(
        &dir,
        &["lines.jsonl", "--progress", "json"],
        &[("SLURM_ARRAY_TASK_ID", "1")],
    );
    assert_eq!(statuses(&slurm).len(), 1);
    let shard = batch(
        &dir,
        &["lines.jsonl", "--shard", "1/3", "--progress", "json"],
        &[],
    );
    assert_eq!(
        statuses(&shard).len(),
        (0..rows.len()).filter(|i| i % 3 == 1).count()
    );
    assert!(!broken.is_empty());
}

/// A local Ray cluster: a head and a second node on this machine, one CPU each, stopped when
/// dropped.
struct RayCluster {
    address: String,
    temp: PathBuf,
}

impl RayCluster {
    fn start() -> RayCluster {
        let port = free_tcp_port();
        let temp = std::env::temp_dir().join(format!("faceanim-ray-{}", std::process::id()));
        let address = format!("127.0.0.1:{port}");
        let ray = |args: &[&str]| {
            support::succeeded(
                "ray start (pip install ray: scripts/setup.sh)",
                Command::new("ray")
                    .args(args)
                    .env("RAY_USAGE_STATS_ENABLED", "0")
                    .output()
                    .expect("ray is needed: run scripts/setup.sh"),
            );
        };
        let cluster = RayCluster {
            address: address.clone(),
            temp: temp.clone(),
        };
        ray(&[
            "start",
            "--head",
            "--node-ip-address",
            "127.0.0.1",
            "--port",
            &port.to_string(),
            "--num-cpus",
            "1",
            "--include-dashboard",
            "false",
            "--disable-usage-stats",
            "--temp-dir",
            temp.to_str().unwrap(),
        ]);
        ray(&[
            "start",
            "--address",
            &address,
            "--node-ip-address",
            "127.0.0.1",
            "--num-cpus",
            "1",
        ]);
        cluster
    }
}

impl Drop for RayCluster {
    fn drop(&mut self) {
        let _ = Command::new("ray").args(["stop", "--force"]).output();
        let _ = std::fs::remove_dir_all(&self.temp);
    }
}

fn free_tcp_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

#[test]
fn on_a_ray_cluster_every_row_is_done_once_though_a_worker_is_killed() {
    let (dir, made) = lines("batch-ray", count().min(16), 3);
    let (good, broken) = good_and_broken(&made);
    // A faceanim that notes each start of a row (to count them), and whose first start of one
    // good row hangs until its Ray worker is killed, as a node lost mid-row.
    let stuck = index_of(&made, &good[good.len() / 2]);
    let starts = dir.join("starts.log");
    let wrapper = dir.join("faceanim-logged");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\n\
             [ \"$3\" = --index ] && echo \"$4 $$\" >> '{log}'\n\
             if [ \"$3\" = --index ] && [ \"$4\" = {stuck} ] && mkdir '{marker}' 2>/dev/null; then exec sleep 600; fi\n\
             exec '{faceanim}' \"$@\"\n",
            log = starts.display(),
            marker = dir.join("stuck-once").display(),
            faceanim = env!("CARGO_BIN_EXE_faceanim"),
        ),
    )
    .unwrap();
    std::fs::set_permissions(
        &wrapper,
        std::os::unix::fs::PermissionsExt::from_mode(0o755),
    )
    .unwrap();
    let cluster = RayCluster::start();
    let mut driver = Command::new("python3")
        .arg(support::repo().join("deploy/ray/faceanim_ray.py"))
        .arg(dir.join("lines.jsonl"))
        .args([
            "--faceanim",
            wrapper.to_str().unwrap(),
            "--address",
            &cluster.address,
        ])
        .env("RAY_USAGE_STATS_ENABLED", "0")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // When the stuck row has started, kill the Ray worker running it.
    let deadline = Instant::now() + Duration::from_secs(240);
    loop {
        assert!(Instant::now() < deadline, "the stuck row never started");
        if driver.try_wait().unwrap().is_some() {
            let out = driver.wait_with_output().unwrap();
            panic!(
                "the driver ended before the stuck row started: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        let log = std::fs::read_to_string(&starts).unwrap_or_default();
        let pid = log
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{stuck} ")).map(str::to_owned));
        if let Some(pid) = pid {
            let parent = Command::new("ps")
                .args(["-o", "ppid=", "-p", &pid])
                .output()
                .unwrap();
            let worker = String::from_utf8_lossy(&parent.stdout).trim().to_owned();
            let name =
                std::fs::read_to_string(format!("/proc/{worker}/cmdline")).unwrap_or_default();
            assert!(
                name.contains("ray::run_row"),
                "the row's parent is not a Ray worker: {name:?}"
            );
            assert!(
                Command::new("kill")
                    .args(["-9", &worker])
                    .status()
                    .unwrap()
                    .success()
            );
            // The row's process dies with its worker (the driver's parent-death signal): no
            // leftover runs beside the retry.
            let gone = Instant::now() + Duration::from_secs(20);
            while Path::new(&format!("/proc/{pid}")).exists() {
                assert!(
                    Instant::now() < gone,
                    "the killed worker's row process {pid} lives on"
                );
                std::thread::sleep(Duration::from_millis(20));
            }
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = driver.wait_with_output().unwrap();
    drop(cluster);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(i32::from(EXIT_BAD_INPUT)),
        "{stderr}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("lines.jsonl.ray-report.json")).unwrap())
            .unwrap();
    let rows = report["rows"].as_array().unwrap();
    assert_eq!(rows.len(), good.len() + broken.len());
    let status: BTreeMap<&str, &str> = rows
        .iter()
        .map(|r| (r["id"].as_str().unwrap(), r["status"].as_str().unwrap()))
        .collect();
    for id in &good {
        assert_eq!(status[id.as_str()], "done", "{id}: {stderr}");
    }
    for id in &broken {
        assert_eq!(status[id.as_str()], "bad_input", "{id}");
    }
    assert!(
        rows.iter()
            .filter(|r| r["status"] == "bad_input")
            .all(|r| r["exit"] == 42)
    );
    // Starts per row: the killed row twice (its first start died with its worker), a broken
    // row at most once (never retried), every other row once.
    let mut started: BTreeMap<String, usize> = BTreeMap::new();
    for line in std::fs::read_to_string(&starts).unwrap().lines() {
        *started
            .entry(line.split(' ').next().unwrap().to_owned())
            .or_default() += 1;
    }
    for id in &good {
        let index = index_of(&made, id);
        let expected = if index == stuck { 2 } else { 1 };
        assert_eq!(
            started.get(&index).copied().unwrap_or(0),
            expected,
            "{id} (row {index})"
        );
    }
    for id in &broken {
        assert!(
            started.get(&index_of(&made, id)).copied().unwrap_or(0) <= 1,
            "{id} was retried"
        );
    }
    // Nothing is corrupt: every take whole, no staged file left.
    assert_takes(&dir, &good);
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary.contains(&format!("{} done", good.len())),
        "{summary}"
    );
}

/// Makes `path` from ffmpeg's lavfi `source`, with the output options `more`.
fn lavfi(source: &str, more: &[&str], path: &Path) {
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "lavfi", "-i", source])
        .args(more)
        .arg(path)
        .output();
    support::succeeded("ffmpeg", made.unwrap());
}

/// A row whose output cannot be made for its character (a VRM Animation of the built-in head,
/// which is no VRM) is bad input named by the output the user wrote, not the hidden name it is
/// staged under; a VRM avatar's row writes one.
#[test]
fn a_row_that_fails_names_its_own_output() {
    let dir = support::output_dir("batch-named-output");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let wav = dir.join("line.wav");
    support::flite("slt", "Bring me the blue paper.", &wav);
    let avatar = dir.join("hero.vrm");
    std::fs::write(
        &avatar,
        faceanim_testdata::producers::with_vrm(
            faceanim_testdata::producers::blender_avatar(),
            faceanim_testdata::avatar::VrmKind::V1,
        ),
    )
    .unwrap();
    let silence = dir.join("silence.wav");
    lavfi("anullsrc=r=16000:cl=mono", &["-t", "1"], &silence);
    // A picture with no face in it: ffmpeg's test pattern.
    lavfi(
        "testsrc=size=320x240",
        &["-frames:v", "1"],
        &dir.join("pattern.png"),
    );
    let manifest = [
        r#"{"id": "head", "kind": "lipsync", "speech": "line.wav", "text": "Bring me the blue paper.", "outputs": "out/head.vrma"}"#,
        r#"{"id": "hero", "kind": "lipsync", "speech": "line.wav", "text": "Bring me the blue paper.", "character": "hero.vrm", "outputs": "out/hero.vrma"}"#,
        r#"{"id": "quiet", "kind": "lipsync", "speech": "silence.wav", "outputs": "out/quiet.json"}"#,
        r#"{"id": "nobody", "kind": "track", "video": "pattern.png", "outputs": "out/nobody.json"}"#,
    ]
    .join("\n");
    std::fs::write(dir.join("rows.jsonl"), manifest).unwrap();
    let out = batch(&dir, &["rows.jsonl", "--progress", "json"], &[]);
    assert_exit(&out, EXIT_BAD_INPUT, "the run");
    let events = row_events(&out);
    assert_eq!(events["hero"][0]["status"], "done", "{:?}", events["hero"]);
    // A row done with something to heed says it in the report: silence leaves the mouth shut.
    let quiet = &events["quiet"][0];
    assert_eq!(quiet["status"], "done", "{quiet}");
    let notes: Vec<&str> = quiet["notes"]
        .as_array()
        .map(|n| n.iter().filter_map(serde_json::Value::as_str).collect())
        .unwrap_or_default();
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with("note: ") && n.contains("no voice was heard")),
        "{quiet}"
    );
    // A warning (a picture with no face in it) is in the summary too: the row needs a look.
    let nobody = events["nobody"][0].to_string();
    assert!(
        nobody.contains("\"done\"") && nobody.contains("warning: ") && nobody.contains("no face"),
        "{nobody}"
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary
            .lines()
            .any(|l| l.starts_with("  line 4 (nobody): done: warning: ") && l.contains("no face")),
        "{summary}"
    );
    // Notes name the outputs as the manifest does, not as they were staged.
    let hero = events["hero"][0]["notes"].to_string();
    assert!(
        hero.contains("out/hero.vrma") && !hero.contains(faceanim_batch::record::STAGED_PREFIX),
        "{hero}"
    );
    let error = events["head"][0]["error"].as_str().unwrap();
    assert!(
        error.starts_with("out/head.vrma: ") && error.contains("is no VRM avatar"),
        "{error}"
    );
    assert!(
        !error.contains(faceanim_batch::record::STAGED_PREFIX),
        "{error}"
    );
    assert!(dir.join("out/hero.vrma").is_file());

    // One command's outputs alike: what the character cannot take is refused (the built-in
    // head), and every file is made before any is written (silence on the VRM avatar: nothing
    // for a VRM Animation to carry, and no clip beside it).
    let [clip, vrma] = ["json", "vrma"].map(|e| dir.join(format!("out/alone.{e}")));
    let (clip_path, vrma_path) = (clip.to_str().unwrap(), vrma.to_str().unwrap());
    for (speech, character, problem) in [
        (&wav, None, "is no VRM avatar"),
        (&silence, Some(&avatar), "nothing in the animation moves"),
    ] {
        let mut args = vec!["lipsync", speech.to_str().unwrap(), "-o", clip_path];
        args.extend(["-o", vrma_path]);
        if let Some(avatar) = character {
            args.extend(["--character", avatar.to_str().unwrap()]);
        }
        let out = support::faceanim(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let said = format!("error: {vrma_path}: ");
        assert_eq!(out.status.code(), Some(1), "{problem}: {stderr}");
        assert!(
            stderr.contains(&said) && stderr.contains(problem),
            "{stderr}"
        );
        assert!(!clip.exists(), "{problem}: the clip was written");
    }
}
