//! The record beside each output: unchanged rows skipped, changed ones redone, edits kept, and a
//! worker stopped halfway neither skips its row nor takes its own files for edits.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

use faceanim_batch::manifest::Manifest;
use faceanim_batch::record::{self, Planner, Policy, Reason, State};

/// `--force`.
const FORCE: Policy = Policy {
    force: true,
    overwrite_edits: false,
};

/// `--overwrite-edits`.
const OVERWRITE_EDITS: Policy = Policy {
    force: false,
    overwrite_edits: true,
};

/// A manifest of one lipsync row writing two outputs, in a fresh folder.
fn one_row() -> (tempfile::TempDir, Manifest) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.wav"), b"first take").unwrap();
    let path = dir.path().join("lines.jsonl");
    std::fs::write(
        &path,
        r#"{"id": "a", "kind": "lipsync", "speech": "a.wav", "text": "Hi there", "outputs": ["out/a.json", "out/a.csv"]}"#,
    )
    .unwrap();
    let manifest = Manifest::read(&path).unwrap();
    (dir, manifest)
}

/// Runs the row as a worker would, writing `bytes` to each output.
fn write_row(planner: &Planner, manifest: &Manifest, bytes: &[u8]) {
    let row = manifest.rows().next().unwrap();
    let _lock = record::lock(row).unwrap();
    let staged = record::staged_paths(row);
    for path in &staged {
        std::fs::write(path, bytes).unwrap();
    }
    planner.commit(row, &staged).unwrap();
    for path in &staged {
        assert!(!path.exists(), "{} was renamed into place", path.display());
    }
}

/// [`one_row`] written once ("take 1"), with its planner.
fn written_once() -> (tempfile::TempDir, Manifest, Planner) {
    let (dir, manifest) = one_row();
    let planner = Planner::new("1.0.0");
    write_row(&planner, &manifest, b"take 1");
    (dir, manifest, planner)
}

#[test]
fn a_row_is_redone_only_when_something_it_depends_on_changed() {
    let (dir, manifest) = one_row();
    let planner = Planner::new("1.0.0");
    let row = manifest.rows().next().unwrap();
    let state = |planner: &Planner, policy| planner.state(row, policy).unwrap();
    assert_eq!(state(&planner, Policy::default()), State::ToDo(Reason::New));
    write_row(&planner, &manifest, b"take 1");
    assert_eq!(state(&planner, Policy::default()), State::Done);
    assert!(dir.path().join("out/a.json.made.json").is_file());
    assert_eq!(state(&planner, FORCE), State::ToDo(Reason::Forced));
    // Another version of faceanim redoes it.
    assert!(matches!(
        state(&Planner::new("1.1.0"), Policy::default()),
        State::ToDo(Reason::Changed(what)) if what.contains("1.0.0 → 1.1.0")
    ));
    // A changed input (a fresh planner: one run hashes each input once).
    std::fs::write(dir.path().join("a.wav"), b"second take").unwrap();
    let planner = Planner::new("1.0.0");
    assert_eq!(
        state(&planner, Policy::default()),
        State::ToDo(Reason::Changed("a.wav".to_owned()))
    );
    write_row(&planner, &manifest, b"take 2");
    assert_eq!(state(&planner, Policy::default()), State::Done);
    // An output gone.
    std::fs::remove_file(dir.path().join("out/a.csv")).unwrap();
    assert_eq!(
        state(&planner, Policy::default()),
        State::ToDo(Reason::Missing("out/a.csv".to_owned()))
    );
}

#[test]
fn an_edited_output_is_kept_unless_asked() {
    let (dir, manifest, _) = written_once();
    let row = manifest.rows().next().unwrap();
    std::fs::write(dir.path().join("out/a.json"), b"polished by hand").unwrap();
    // Even with --force, and even when an input changed too.
    std::fs::write(dir.path().join("a.wav"), b"second take").unwrap();
    let planner = Planner::new("1.0.0");
    for force in [false, true] {
        let policy = Policy {
            force,
            ..Policy::default()
        };
        assert_eq!(
            planner.state(row, policy).unwrap(),
            State::Edited(vec!["out/a.json".to_owned()])
        );
    }
    assert_eq!(
        planner.state(row, OVERWRITE_EDITS).unwrap(),
        State::ToDo(Reason::OverwritingEdits)
    );
}

#[test]
fn a_file_the_batch_did_not_write_is_not_overwritten() {
    let (dir, manifest) = one_row();
    std::fs::create_dir_all(dir.path().join("out")).unwrap();
    std::fs::write(dir.path().join("out/a.csv"), b"made by hand").unwrap();
    let planner = Planner::new("1.0.0");
    let row = manifest.rows().next().unwrap();
    assert_eq!(
        planner.state(row, Policy::default()).unwrap(),
        State::Edited(vec!["out/a.csv".to_owned()])
    );
}

#[test]
fn a_worker_stopped_while_writing_leaves_a_row_that_is_redone_not_edited() {
    let (dir, manifest, planner) = written_once();
    let row = manifest.rows().next().unwrap();
    // The next run staged new outputs and wrote its `writing` record, renamed the first
    // output, and was killed before the second rename and the final record.
    let record_path = record::record_path(row);
    let mut record: record::Record =
        serde_json::from_slice(&std::fs::read(&record_path).unwrap()).unwrap();
    let old = record.outputs.clone();
    let staged = record::staged_paths(row);
    for path in &staged {
        std::fs::write(path, b"take 2").unwrap();
    }
    let new_hash = {
        // The hash the commit would record, taken from a finished commit elsewhere.
        let (_other, other_manifest) = one_row();
        let other = Planner::new("1.0.0");
        write_row(&other, &other_manifest, b"take 2");
        let other_row = other_manifest.rows().next().unwrap();
        let done: record::Record =
            serde_json::from_slice(&std::fs::read(record::record_path(other_row)).unwrap())
                .unwrap();
        done.outputs
    };
    record.outputs = new_hash;
    record.replacing = old;
    record.writing = true;
    std::fs::write(&record_path, serde_json::to_vec(&record).unwrap()).unwrap();
    std::fs::rename(&staged[0], dir.path().join("out/a.json")).unwrap();
    // One output new, one old: both the batch's, and the row runs again.
    assert_eq!(
        planner.state(row, Policy::default()).unwrap(),
        State::ToDo(Reason::Interrupted)
    );
    write_row(&planner, &manifest, b"take 2");
    assert_eq!(planner.state(row, Policy::default()).unwrap(), State::Done);
    assert_eq!(
        std::fs::read(dir.path().join("out/a.csv")).unwrap(),
        b"take 2"
    );
}

#[test]
fn input_found_bad_is_reported_again_without_running_until_it_changes() {
    let (dir, manifest, _) = written_once();
    let row = manifest.rows().next().unwrap();
    // The line re-delivered broken: the run finds it bad and says so.
    std::fs::write(dir.path().join("a.wav"), b"not a sound").unwrap();
    let planner_now = Planner::new("1.0.0");
    assert!(matches!(
        planner_now.state(row, Policy::default()).unwrap(),
        State::ToDo(_)
    ));
    planner_now.remember_bad(row, "a.wav: not a sound").unwrap();
    assert_eq!(
        planner_now.state(row, Policy::default()).unwrap(),
        State::Bad("a.wav: not a sound".to_owned())
    );
    // The outputs the earlier run wrote are still the batch's, not edits.
    assert!(dir.path().join("out/a.json").is_file());
    // Fixed, it runs again; --force runs it anyway.
    assert_eq!(
        planner_now.state(row, FORCE).unwrap(),
        State::ToDo(Reason::Forced)
    );
    std::fs::write(dir.path().join("a.wav"), b"a good take").unwrap();
    assert!(matches!(
        Planner::new("1.0.0").state(row, Policy::default()).unwrap(),
        State::ToDo(Reason::Changed(_))
    ));
}
