//! The checkpoint of a run with load steps (docs/problem-format.md §6): an
//! index `NAME.h5` of external links to `NAME_mesh.h5` and one file per
//! step, so that a step writes its own data only; the set read as one file,
//! moved as a whole, restarted from in place without rewriting the steps
//! it holds, and older single-file checkpoints still restarted from.

mod common;

use common::run;
use signorini::io::hdf5::{
    append_step, append_step_with_friction_in_place, create_checkpoint, read_checkpoint, Checkpoint,
};
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
fn bits(s: &signorini::io::StepOutput) -> Vec<u64> {
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
