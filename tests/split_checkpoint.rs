//! The checkpoint of a run with load steps (docs/problem-format.md §6): an
//! index `NAME.h5` of external links to `NAME_mesh.h5` and one file per
//! step, so that a step writes its own data only; the set read as one file,
//! moved as a whole, restarted from in place without rewriting the steps
//! it holds, and older single-file checkpoints still restarted from.

mod common;

use common::run;
use signorini::io::hdf5::{
    append_step, append_step_with_friction_in_place, create_checkpoint, read_checkpoint,
};
use signorini::output::Checkpoint;
use std::os::unix::fs::MetadataExt;
use std::path::Path;

const NAME: &str = "three_bodies_steps";

fn example() -> String {
    common::example(NAME)
}

fn solve(out: &Path, extra: &[&str]) {
    let e = example();
    let mut args = vec![
        "solve",
        e.as_str(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let (code, log) = run(&args);
    assert_eq!(code, 0, "{log}");
}

/// The bits of a step's displacements, stresses and multipliers.
fn bits(s: &signorini::output::StepOutput) -> Vec<u64> {
    s.displacement
        .iter()
        .flatten()
        .chain(s.stress.iter().flatten())
        .chain(&s.multipliers)
        .map(|x| x.to_bits())
        .collect()
}

/// `got` holds the steps of the uninterrupted run `want`: the first `held`
/// (those the restart took from its checkpoint) bit for bit, the others
/// (solved again from a warm start) to 1e-8 of the largest displacement.
fn same_run(got: &Checkpoint, want: &Checkpoint, held: usize) {
    assert_eq!(got.steps.len(), want.steps.len());
    let scale = want.steps.last().map_or(1.0, |s| {
        s.displacement
            .iter()
            .fold(0.0f64, |m, u| m.max(u[0].abs()).max(u[1].abs()))
    });
    for (k, (a, b)) in got.steps.iter().zip(&want.steps).enumerate() {
        if k < held {
            assert!(bits(a) == bits(b), "step {} changed", k + 1);
        }
        for (p, q) in a.displacement.iter().zip(&b.displacement) {
            assert!(
                (p[0] - q[0]).abs() <= 1e-8 * scale && (p[1] - q[1]).abs() <= 1e-8 * scale,
                "step {}: {p:?} vs {q:?}",
                k + 1
            );
        }
        assert_eq!(a.time, b.time);
    }
}

/// (inode, bytes) of a file.
fn identity(p: &Path) -> (u64, Vec<u8>) {
    (
        std::fs::metadata(p).unwrap().ino(),
        std::fs::read(p).unwrap(),
    )
}

#[test]
fn a_step_writes_its_own_file_and_a_small_index() {
    let d = tempfile::tempdir().unwrap();
    solve(d.path(), &[]);
    let index = std::fs::metadata(d.path().join(format!("{NAME}.h5")))
        .unwrap()
        .len();
    let mesh = std::fs::metadata(d.path().join(format!("{NAME}_mesh.h5")))
        .unwrap()
        .len();
    for k in 1..=4 {
        let step = d.path().join(format!("{NAME}_{k:04}.h5"));
        let len = std::fs::metadata(&step).unwrap().len();
        // The index holds links and attributes, no step data.
        assert!(index < len, "index {index} bytes, step {k} {len} bytes");
        // A step file holds its own group only.
        let f = hdf5::File::open(&step).unwrap();
        assert_eq!(
            f.group("steps").unwrap().member_names().unwrap(),
            vec![format!("{k:04}")]
        );
        assert!(!f.link_exists("mesh"), "step {k} file holds the mesh");
    }
    assert!(index < mesh, "index {index} bytes, mesh {mesh} bytes");
    let ck = read_checkpoint(&d.path().join(format!("{NAME}.h5"))).unwrap();
    assert_eq!(ck.steps.len(), 4);
    assert_eq!(ck.step_groups, vec!["0001", "0002", "0003", "0004"]);
}

#[test]
fn a_restart_in_place_keeps_the_steps_it_holds_and_a_moved_set_still_reads() {
    let full = tempfile::tempdir().unwrap();
    solve(full.path(), &[]);
    let want = read_checkpoint(&full.path().join(format!("{NAME}.h5"))).unwrap();

    let part = tempfile::tempdir().unwrap();
    solve(part.path(), &["--max-steps", "2"]);
    let kept = [
        format!("{NAME}_mesh.h5"),
        format!("{NAME}_0001.h5"),
        format!("{NAME}_0002.h5"),
    ];
    let before: Vec<_> = kept
        .iter()
        .map(|n| identity(&part.path().join(n)))
        .collect();
    let h5 = part.path().join(format!("{NAME}.h5"));
    solve(part.path(), &["--restart", h5.to_str().unwrap()]);
    // Neither rewritten nor replaced: the same files, the same bytes.
    for (n, b) in kept.iter().zip(&before) {
        assert!(
            identity(&part.path().join(n)) == *b,
            "{n} was written again"
        );
    }
    let got = read_checkpoint(&h5).unwrap();
    same_run(&got, &want, 2);

    // The set moved as a whole reads the same (the links are relative).
    let moved = tempfile::tempdir().unwrap();
    let to = moved.path().join("elsewhere");
    std::fs::rename(part.path(), &to).unwrap_or_else(|_| {
        std::fs::create_dir(&to).unwrap();
        for e in std::fs::read_dir(part.path()).unwrap().flatten() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    });
    let again = read_checkpoint(&to.join(format!("{NAME}.h5"))).unwrap();
    same_run(&again, &got, 4);
}

/// A checkpoint in the single-file layout (a single solve's, or one an
/// older signorini wrote for a run with load steps) is restarted from: the
/// run writes the split layout with its steps taken out, and ends where an
/// uninterrupted run ends.
#[test]
fn a_single_file_checkpoint_with_steps_is_restarted_from() {
    let full = tempfile::tempdir().unwrap();
    solve(full.path(), &[]);
    let want = read_checkpoint(&full.path().join(format!("{NAME}.h5"))).unwrap();

    let part = tempfile::tempdir().unwrap();
    solve(part.path(), &["--max-steps", "2"]);
    let split = read_checkpoint(&part.path().join(format!("{NAME}.h5"))).unwrap();
    // The same checkpoint written as one file, in another directory.
    let old = tempfile::tempdir().unwrap();
    let single = old.path().join(format!("{NAME}.h5"));
    let attrs: Vec<(&str, String)> = split
        .attrs
        .iter()
        .map(|(k, v)| (k.as_str(), v.clone()))
        .collect();
    create_checkpoint(&single, &split.mesh, &attrs).unwrap();
    for (k, (s, f)) in split.steps.iter().zip(&split.friction).enumerate() {
        match f {
            Some(f) => append_step_with_friction_in_place(&single, k + 1, s, f).unwrap(),
            None => append_step(&single, k + 1, s).unwrap(),
        }
    }
    assert_eq!(
        std::fs::read_dir(old.path()).unwrap().count(),
        1,
        "one file"
    );

    let out = tempfile::tempdir().unwrap();
    solve(out.path(), &["--restart", single.to_str().unwrap()]);
    let got = read_checkpoint(&out.path().join(format!("{NAME}.h5"))).unwrap();
    same_run(&got, &want, 2);
    for k in 1..=4 {
        assert!(
            out.path().join(format!("{NAME}_{k:04}.h5")).is_file(),
            "step {k} file"
        );
    }
    // The single file is left as it was.
    assert_eq!(read_checkpoint(&single).unwrap().steps.len(), 2);
}

// ------------------------------------------------- files from another run
//
// Issue 43: the output transaction owns every file of its name's pattern
// (NAME.vtu, NAME_NNNN.vtu, NAME_NNNN_contact.vtu, NAME_NNNN.h5,
// NAME_mesh.h5, NAME.pvd): a run removes what an older run of the same
// name left that it does not write or keep, and every file a .pvd names
// lies beside it.

/// `dir/NAME.toml`: three_bodies_steps with `nsteps` load steps (0: none,
/// a single solve), the mesh path made absolute. The output name is NAME.
fn variant(dir: &Path, nsteps: usize) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(example()).unwrap();
    let head = &text[..text.find("[[steps]]").unwrap()];
    let mesh = common::meshes().join("three_bodies.msh");
    let mut out = head.replace(
        "file = \"three_bodies.msh\"",
        &format!("file = {:?}", mesh.to_str().unwrap()),
    );
    for k in 1..=nsteps {
        out.push_str(&format!(
            "[[steps]]\nt = {k}.0\ndisplacement = {}\nload = 1.0\n\n",
            k as f64 / nsteps as f64
        ));
    }
    let p = dir.join(format!("{NAME}.toml"));
    std::fs::write(&p, out).unwrap();
    p
}

fn solve_toml(toml: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args = vec![
        "solve",
        toml.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    run(&args)
}

/// The sorted file names in `dir`.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The files a complete run of `nsteps` load steps leaves (0: a single solve).
fn expected_set(nsteps: usize) -> Vec<String> {
    let mut v = vec![format!("{NAME}.h5"), format!("{NAME}.json")];
    if nsteps == 0 {
        v.extend([format!("{NAME}.vtu"), format!("{NAME}_contact.vtu")]);
    } else {
        v.extend([format!("{NAME}.pvd"), format!("{NAME}_mesh.h5")]);
        for k in 1..=nsteps {
            v.extend([
                format!("{NAME}_{k:04}.h5"),
                format!("{NAME}_{k:04}.vtu"),
                format!("{NAME}_{k:04}_contact.vtu"),
            ]);
        }
    }
    v.sort();
    v
}

/// Every file the .pvd of `dir` names exists beside it; returns the names.
fn pvd_entries_exist(dir: &Path) -> Vec<String> {
    let pvd = dir.join(format!("{NAME}.pvd"));
    let entries = signorini::io::vtu::read_pvd(&pvd).unwrap();
    for (_, f) in &entries {
        let p = pvd.parent().unwrap().join(f);
        assert!(
            p.is_file(),
            "{} names {f}, which is not beside it",
            pvd.display()
        );
    }
    entries.into_iter().map(|e| e.1).collect()
}

#[test]
fn a_shorter_run_removes_the_files_of_an_older_longer_run() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let long = variant(&d.path().join("long"), 20);
    let short = variant(&d.path().join("short"), 5);
    let (code, log) = solve_toml(&long, &out, &[]);
    assert_eq!(code, 0, "{log}");
    assert_eq!(listing(&out), expected_set(20));
    let (code, log) = solve_toml(&short, &out, &[]);
    assert_eq!(code, 0, "{log}");
    // Was 64 files: 45 of them the 20-step run's steps 6..20.
    assert_eq!(listing(&out), expected_set(5));
    assert_eq!(pvd_entries_exist(&out).len(), 10);
    assert_eq!(
        read_checkpoint(&out.join(format!("{NAME}.h5")))
            .unwrap()
            .steps
            .len(),
        5
    );
}

#[test]
fn a_single_solve_and_a_stepped_run_remove_each_others_files() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let stepped = variant(&d.path().join("stepped"), 3);
    let single = variant(&d.path().join("single"), 0);
    assert_eq!(solve_toml(&stepped, &out, &[]).0, 0);
    assert_eq!(listing(&out), expected_set(3));
    assert_eq!(solve_toml(&single, &out, &[]).0, 0);
    assert_eq!(listing(&out), expected_set(0));
    assert_eq!(solve_toml(&stepped, &out, &[]).0, 0);
    assert_eq!(listing(&out), expected_set(3));
}

#[test]
fn a_run_stopped_by_max_steps_leaves_no_later_step_of_an_older_run_and_restarts() {
    let d = tempfile::tempdir().unwrap();
    solve(d.path(), &[]);
    assert_eq!(listing(d.path()), expected_set(4));
    solve(d.path(), &["--max-steps", "2"]);
    assert_eq!(listing(d.path()), expected_set(2));
    assert_eq!(pvd_entries_exist(d.path()).len(), 4);
    let h5 = d.path().join(format!("{NAME}.h5"));
    solve(d.path(), &["--restart", h5.to_str().unwrap()]);
    assert_eq!(listing(d.path()), expected_set(4));
    assert_eq!(pvd_entries_exist(d.path()).len(), 8);
}

#[test]
fn a_restart_into_another_folder_brings_the_pairs_its_pvd_lists() {
    let d = tempfile::tempdir().unwrap();
    let (first, second) = (d.path().join("first"), d.path().join("second"));
    let long = variant(&d.path().join("long"), 20);
    let five = variant(&d.path().join("five"), 5);
    assert_eq!(solve_toml(&five, &first, &["--max-steps", "3"]).0, 0);
    // The second folder holds an older, longer run of the same name.
    assert_eq!(solve_toml(&long, &second, &[]).0, 0);
    let h5 = first.join(format!("{NAME}.h5"));
    let (code, log) = solve_toml(&five, &second, &["--restart", h5.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    assert_eq!(listing(&second), expected_set(5));
    assert_eq!(pvd_entries_exist(&second).len(), 10);
    // Steps 1..3 are the first folder's pairs, copied as they are.
    for k in 1..=3 {
        for f in [
            format!("{NAME}_{k:04}.vtu"),
            format!("{NAME}_{k:04}_contact.vtu"),
        ] {
            assert!(
                std::fs::read(first.join(&f)).unwrap() == std::fs::read(second.join(&f)).unwrap(),
                "{f} differs from the first folder's"
            );
        }
    }
    // A checkpoint without its pairs (packed and moved alone): the pairs
    // are written again from its steps, the displacements bit for bit.
    let alone = d.path().join("alone");
    std::fs::create_dir(&alone).unwrap();
    let packed = alone.join("packed.h5");
    let (code, log) = run(&["pack", h5.to_str().unwrap(), "-o", packed.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    let third = d.path().join("third");
    let (code, log) = solve_toml(&five, &third, &["--restart", packed.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    assert_eq!(listing(&third), expected_set(5));
    assert_eq!(pvd_entries_exist(&third).len(), 10);
    for k in 1..=3 {
        let f = format!("{NAME}_{k:04}.vtu");
        let a = signorini::io::vtu::read_vtu_arrays(&first.join(&f)).unwrap();
        let b = signorini::io::vtu::read_vtu_arrays(&third.join(&f)).unwrap();
        assert_eq!(a.num_points, b.num_points);
        let (ua, ub) = (a.point_array("displacement"), b.point_array("displacement"));
        assert!(ua.is_some() && ua == ub, "{f}: displacements differ");
    }
}

/// The packed checkpoint of a split one, moved alone to another directory:
/// the same tree bit for bit, restarted from (to the uninterrupted run's
/// end), drawn by `plot`, and exported as VTU pairs by a restart with
/// nothing left to solve.
#[test]
fn a_packed_checkpoint_travels_alone() {
    let d = tempfile::tempdir().unwrap();
    let full = d.path().join("full");
    solve(&full, &[]);
    let want = read_checkpoint(&full.join(format!("{NAME}.h5"))).unwrap();
    let part = d.path().join("part");
    solve(&part, &["--max-steps", "2"]);
    let h5 = part.join(format!("{NAME}.h5"));
    let staging = d.path().join("staging");
    std::fs::create_dir(&staging).unwrap();
    let packed = staging.join("one.h5");
    let (code, log) = run(&["pack", h5.to_str().unwrap(), "-o", packed.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    assert!(log.contains("2 step(s)"), "{log}");
    // Moved alone: nothing else in its directory.
    let travel = d.path().join("travel");
    std::fs::create_dir(&travel).unwrap();
    let moved = travel.join("one.h5");
    std::fs::rename(&packed, &moved).unwrap();
    assert_eq!(listing(&travel), vec!["one.h5".to_string()]);
    let orig = read_checkpoint(&h5).unwrap();
    let got = read_checkpoint(&moved).unwrap();
    assert_eq!(got.step_groups, orig.step_groups);
    assert_eq!(got.attrs, orig.attrs);
    for (a, b) in got.steps.iter().zip(&orig.steps) {
        assert!(bits(a) == bits(b));
        assert_eq!(a.info.method, b.info.method);
    }
    // No external link is left: every /steps member is a hard link.
    {
        let f = hdf5::File::open(&moved).unwrap();
        let mut kinds = vec![];
        f.group("steps")
            .unwrap()
            .iter_visit_default(|_, info| {
                kinds.push(info.link_type);
                Ok(())
            })
            .unwrap();
        assert!(
            kinds.iter().all(|k| *k == hdf5::LinkType::Hard),
            "{kinds:?}"
        );
    }
    // restart
    let out = d.path().join("restarted");
    solve(&out, &["--restart", moved.to_str().unwrap()]);
    let done = read_checkpoint(&out.join(format!("{NAME}.h5"))).unwrap();
    same_run(&done, &want, 2);
    // plot
    let png = d.path().join("one.png");
    let (code, log) = run(&["plot", moved.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    assert!(std::fs::metadata(&png).unwrap().len() > 0);
    // export: a restart with nothing to solve writes the pairs and series.
    let exported = d.path().join("exported");
    solve(
        &exported,
        &["--restart", moved.to_str().unwrap(), "--max-steps", "2"],
    );
    assert_eq!(pvd_entries_exist(&exported).len(), 4);
    assert_eq!(
        read_checkpoint(&exported.join(format!("{NAME}.h5")))
            .unwrap()
            .steps
            .len(),
        2
    );
    // The packed file is left as it was.
    assert_eq!(listing(&travel), vec!["one.h5".to_string()]);
}

/// A split checkpoint missing one step file: `solve --restart`, `plot` and
/// `pack` each refuse it with exit 2, naming that file; pack writes nothing.
#[test]
fn a_missing_step_file_is_named_by_every_reader() {
    let d = tempfile::tempdir().unwrap();
    let part = d.path().join("part");
    solve(&part, &["--max-steps", "3"]);
    std::fs::remove_file(part.join(format!("{NAME}_0002.h5"))).unwrap();
    let h5 = part.join(format!("{NAME}.h5"));
    let missing = part.join(format!("{NAME}_0002.h5"));
    let want = missing.to_str().unwrap();
    let out = d.path().join("out");
    let png = d.path().join("x.png");
    let packed = d.path().join("one.h5");
    for args in [
        vec![
            "solve",
            &example(),
            "--out",
            out.to_str().unwrap(),
            "--restart",
            h5.to_str().unwrap(),
        ],
        vec!["plot", h5.to_str().unwrap(), "-o", png.to_str().unwrap()],
        vec!["pack", h5.to_str().unwrap(), "-o", packed.to_str().unwrap()],
    ] {
        let (code, log) = run(&args);
        assert_eq!(code, 2, "{args:?}: {log}");
        let line = log
            .lines()
            .find(|l| l.starts_with("error"))
            .unwrap_or_default();
        assert!(
            line.contains(want) && line.contains("does not exist") && !log.contains("panicked"),
            "{args:?}: {log}"
        );
    }
    assert!(!packed.exists() && !png.exists());
    // The index itself as the packed file's target is refused too.
    let (code, log) = run(&["pack", h5.to_str().unwrap(), "-o", h5.to_str().unwrap()]);
    assert_eq!(code, 2, "{log}");
}

#[test]
fn pack_refuses_to_write_over_a_file_of_its_own_checkpoint() {
    let d = tempfile::tempdir().unwrap();
    solve(d.path(), &["--max-steps", "2"]);
    let h5 = d.path().join(format!("{NAME}.h5"));
    let before = listing(d.path());
    let step = d.path().join(format!("{NAME}_0001.h5"));
    let bytes = std::fs::read(&step).unwrap();
    for target in [&h5, &step] {
        let (code, log) = run(&["pack", h5.to_str().unwrap(), "-o", target.to_str().unwrap()]);
        assert_eq!(code, 2, "{log}");
        assert!(log.contains("is a file of the checkpoint"), "{log}");
    }
    assert_eq!(listing(d.path()), before);
    assert!(std::fs::read(&step).unwrap() == bytes);
    assert_eq!(read_checkpoint(&h5).unwrap().steps.len(), 2);
}

/// A restart with nothing left to solve into a folder of an older, longer
/// run (an export): the folder ends with the checkpoint's set only, the
/// summary of the run that wrote the checkpoint copied along; from a
/// packed checkpoint moved alone (no summary beside it) the older
/// summary is removed, not left to describe another run.
#[test]
fn a_restart_with_nothing_to_solve_replaces_an_older_runs_set() {
    let d = tempfile::tempdir().unwrap();
    let five = variant(&d.path().join("five"), 5);
    let long = variant(&d.path().join("long"), 20);
    let first = d.path().join("first");
    assert_eq!(solve_toml(&five, &first, &[]).0, 0);
    let h5 = first.join(format!("{NAME}.h5"));
    let second = d.path().join("second");
    assert_eq!(solve_toml(&long, &second, &[]).0, 0);
    let (code, log) = solve_toml(&five, &second, &["--restart", h5.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    assert_eq!(listing(&second), expected_set(5));
    assert_eq!(pvd_entries_exist(&second).len(), 10);
    let json = format!("{NAME}.json");
    assert!(
        std::fs::read(first.join(&json)).unwrap() == std::fs::read(second.join(&json)).unwrap()
    );

    let alone = d.path().join("alone");
    std::fs::create_dir(&alone).unwrap();
    let packed = alone.join("five.h5");
    assert_eq!(
        run(&["pack", h5.to_str().unwrap(), "-o", packed.to_str().unwrap()]).0,
        0
    );
    let third = d.path().join("third");
    assert_eq!(solve_toml(&long, &third, &[]).0, 0);
    let (code, log) = solve_toml(&five, &third, &["--restart", packed.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    // The packed checkpoint copied as one file, the pairs written from it.
    let mut want: Vec<String> = expected_set(5)
        .into_iter()
        .filter(|f| f.ends_with(".vtu") || f.ends_with(".pvd") || *f == format!("{NAME}.h5"))
        .collect();
    want.sort();
    assert_eq!(listing(&third), want);
    assert_eq!(pvd_entries_exist(&third).len(), 10);
    assert_eq!(
        read_checkpoint(&third.join(format!("{NAME}.h5")))
            .unwrap()
            .steps
            .len(),
        5
    );
}

/// Files outside the name's pattern are never touched: another name, a
/// step number of fewer than four digits, another extension.
#[test]
fn files_outside_the_name_pattern_are_left_alone() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let others = [
        format!("{NAME}_notes.txt"),
        format!("{NAME}_0001.png"),
        format!("{NAME}_1.vtu"),
        format!("{NAME}_0009.vtu.bak"),
        "other_0001.vtu".to_string(),
        format!("x{NAME}_0009.vtu"),
    ];
    for (k, f) in others.iter().enumerate() {
        std::fs::write(out.join(f), format!("keep {k}")).unwrap();
    }
    let three = variant(&d.path().join("three"), 3);
    let single = variant(&d.path().join("single"), 0);
    assert_eq!(solve_toml(&three, &out, &[]).0, 0);
    assert_eq!(solve_toml(&single, &out, &[]).0, 0);
    for (k, f) in others.iter().enumerate() {
        assert_eq!(
            std::fs::read_to_string(out.join(f)).unwrap(),
            format!("keep {k}"),
            "{f}"
        );
    }
    let mut want = expected_set(0);
    want.extend(others.iter().cloned());
    want.sort();
    assert_eq!(listing(&out), want);
}

/// A restart in place whose earlier pair was deleted writes it again from
/// the checkpoint, so the .pvd still names only files beside it.
#[test]
fn a_restart_in_place_rewrites_a_deleted_pair() {
    let d = tempfile::tempdir().unwrap();
    solve(d.path(), &["--max-steps", "2"]);
    let vtu = d.path().join(format!("{NAME}_0001.vtu"));
    let kept = std::fs::read(d.path().join(format!("{NAME}_0002.vtu"))).unwrap();
    std::fs::remove_file(&vtu).unwrap();
    let h5 = d.path().join(format!("{NAME}.h5"));
    solve(d.path(), &["--restart", h5.to_str().unwrap()]);
    assert!(vtu.is_file());
    assert_eq!(listing(d.path()), expected_set(4));
    assert_eq!(pvd_entries_exist(d.path()).len(), 8);
    // The pair that was there is kept as it was.
    assert!(std::fs::read(d.path().join(format!("{NAME}_0002.vtu"))).unwrap() == kept);
}

/// A restart in place with nothing left to solve, one pair deleted: the
/// pair is written again and the run's own summary is kept.
#[test]
fn a_finished_restart_in_place_rewrites_a_deleted_pair_and_keeps_its_summary() {
    let d = tempfile::tempdir().unwrap();
    solve(d.path(), &[]);
    let json = std::fs::read(d.path().join(format!("{NAME}.json"))).unwrap();
    std::fs::remove_file(d.path().join(format!("{NAME}_0003_contact.vtu"))).unwrap();
    let h5 = d.path().join(format!("{NAME}.h5"));
    solve(d.path(), &["--restart", h5.to_str().unwrap()]);
    assert_eq!(listing(d.path()), expected_set(4));
    assert_eq!(pvd_entries_exist(d.path()).len(), 8);
    assert!(std::fs::read(d.path().join(format!("{NAME}.json"))).unwrap() == json);
}

/// A part of the set given where a checkpoint is expected (`plot`, `pack`,
/// `--restart`) is refused naming the index to give instead, exit 2, and
/// nothing is written. Before, the reader failed on the first root
/// attribute it needed ("missing attribute /@plane_strain").
#[test]
fn a_part_of_the_set_is_refused_naming_its_index() {
    let d = tempfile::tempdir().unwrap();
    solve(d.path(), &[]);
    let index = d.path().join(format!("{NAME}.h5"));
    for (part, what) in [
        (format!("{NAME}_0002.h5"), "step 2 of"),
        (format!("{NAME}_mesh.h5"), "the mesh of"),
    ] {
        let p = d.path().join(&part);
        let ps = p.to_str().unwrap();
        let png = d.path().join("x.png");
        let packed = d.path().join("packed.h5");
        let again = d.path().join("again");
        let e = example();
        for args in [
            vec!["plot", ps, "-o", png.to_str().unwrap()],
            vec!["pack", ps, "-o", packed.to_str().unwrap()],
            vec![
                "solve",
                e.as_str(),
                "--restart",
                ps,
                "--out",
                again.to_str().unwrap(),
            ],
        ] {
            let (code, log) = run(&args);
            assert_eq!(code, 2, "{args:?}: {log}");
            assert!(
                log.contains("one part of a split checkpoint")
                    && log.contains(&format!("{what} {}", index.display()))
                    && log.contains(&part),
                "{args:?}: {log}"
            );
        }
        assert!(!png.exists() && !packed.exists() && !again.exists());
    }
}
