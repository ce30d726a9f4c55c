//! Faults and hostile files: a full disk, a second run of the same name, a
//! planted symbolic link, crafted checkpoints, a FIFO, too little memory.
//! Whatever happens, a run either completes or exits 2 with one `error:`
//! line, and the output directory then holds exactly what it held before.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{command, exe, joined, meshes, run, run_with_deadline};

/// Exit 2 with exactly one `error:` line and no panic; returns that line.
fn assert_bad_input(code: i32, log: &str, what: &str) -> String {
    assert_eq!(code, 2, "{what}: exit code; log:\n{log}");
    assert!(!log.contains("panicked"), "{what}: a panic:\n{log}");
    let errors: Vec<&str> = log.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{what}: error lines:\n{log}");
    errors[0].to_string()
}

/// Every entry of `dir` (hidden ones included) with its bytes (directories: empty).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let bytes = if e.file_type().unwrap().is_file() {
            std::fs::read(e.path()).unwrap()
        } else {
            vec![]
        };
        m.insert(name, bytes);
    }
    m
}

/// A copy of the shipped problem `name` in `dir`, with the mesh path made
/// absolute and `edits` (from, to) applied to the TOML text.
fn problem_copy(dir: &Path, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(meshes().join(format!("{name}.toml"))).unwrap();
    let start = text.find("\nfile = \"").unwrap() + "\nfile = \"".len();
    let end = start + text[start..].find('"').unwrap();
    let mesh = meshes().join(&text[start..end]);
    text.replace_range(start..end, mesh.to_str().unwrap());
    for (a, b) in edits {
        assert!(text.contains(a), "{name}.toml has no {a:?}");
        text = text.replacen(a, b, 1);
    }
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// A tmpfs mounted for the life of the value.
struct Tmpfs {
    dir: tempfile::TempDir,
}

impl Tmpfs {
    /// None (and a message) when mounting is refused (not root, no tmpfs).
    fn mount(size: &str) -> Option<Tmpfs> {
        let dir = tempfile::tempdir().unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir.path())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("SKIPPED: cannot mount a tmpfs (needs root): the disk-full test did not run");
            return None;
        }
        Some(Tmpfs { dir })
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

/// Fills the file system of `dir` but for about `leave` bytes.
fn fill(dir: &Path, leave: u64) {
    use std::io::Write;
    let mut f = std::fs::File::create(dir.join("filler")).unwrap();
    let chunk = vec![7u8; 4096];
    while f.write_all(&chunk).is_ok() {}
    let _ = f.sync_all();
    let len = f.metadata().unwrap().len();
    f.set_len(len.saturating_sub(leave)).unwrap();
}

#[test]
fn disk_full_leaves_the_previous_results_exactly_as_they_were() {
    let Some(fs) = Tmpfs::mount("8m") else {
        return;
    };
    let out = fs.dir.path().join("out");
    let problem = meshes().join("two_blocks.toml");
    let (code, log) = run(&[
        "solve",
        problem.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
    let before = snapshot(&out);
    assert!(before.contains_key("two_blocks.h5") && before.contains_key("two_blocks.json"));
    let total: usize = before.values().map(Vec::len).sum();
    // Room for a little, not for a new set of outputs: the writes fail part way.
    for leave in [0u64, (total / 3) as u64, (total * 3 / 4) as u64] {
        fill(fs.dir.path(), leave);
        let (code, log) = run(&[
            "solve",
            problem.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--method",
            "mprgp",
            "--quiet",
        ]);
        let line = assert_bad_input(code, &log, &format!("disk full, {leave} bytes left"));
        assert!(line.to_lowercase().contains("no space"), "{line}");
        assert_eq!(
            snapshot(&out),
            before,
            "disk full with {leave} bytes left: the output directory changed"
        );
        std::fs::remove_file(fs.dir.path().join("filler")).unwrap();
    }
    // With room again the same run completes.
    let (code, log) = run(&[
        "solve",
        problem.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
}

#[test]
fn a_second_run_of_the_same_name_fails_at_once_naming_the_holder() {
    use std::io::Write;
    let d = tempfile::tempdir().unwrap();
    let problem = meshes().join("two_blocks.toml");
    let lock_path = d.path().join(".two_blocks.lock");
    let mut held = std::fs::File::create(&lock_path).unwrap();
    held.try_lock().unwrap();
    writeln!(held, "4242").unwrap();
    let t0 = Instant::now();
    let (code, log) = run(&[
        "solve",
        problem.to_str().unwrap(),
        "--out",
        d.path().to_str().unwrap(),
        "--quiet",
    ]);
    let line = assert_bad_input(code, &log, "lock held");
    assert!(
        line.contains("4242") && line.contains("two_blocks"),
        "{line}"
    );
    assert!(
        t0.elapsed() < Duration::from_secs(60),
        "the second run waited"
    );
    let names: Vec<String> = snapshot(d.path()).into_keys().collect();
    assert_eq!(
        names,
        vec![".two_blocks.lock"],
        "the refused run wrote files"
    );
    drop(held);
    std::fs::remove_file(&lock_path).unwrap();

    // Two runs started together: each either completes or is refused by the
    // lock; at least one completes, and the outputs are one run's, whole.
    let steps = meshes().join("three_bodies_steps.toml");
    let spawn = || {
        command()
            .args([
                "solve",
                steps.to_str().unwrap(),
                "--out",
                d.path().to_str().unwrap(),
                "--quiet",
            ])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn(), spawn());
    let results: Vec<(i32, String)> = [a, b]
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            (
                o.status.code().unwrap_or(-1),
                String::from_utf8_lossy(&o.stderr).into_owned(),
            )
        })
        .collect();
    let ok = results.iter().filter(|(c, _)| *c == 0).count();
    assert!(ok >= 1, "{results:?}");
    for (c, err) in &results {
        assert!(
            *c == 0 || (*c == 2 && err.contains("is writing the outputs")),
            "{results:?}"
        );
    }
    let ck = signorini::io::hdf5::read_checkpoint(&d.path().join("three_bodies_steps.h5")).unwrap();
    assert_eq!(ck.steps.len(), 4);
    for (k, s) in ck.steps.iter().enumerate() {
        assert_eq!(s.time, (k + 1) as f64, "interleaved steps");
    }
    let left: Vec<String> = snapshot(d.path())
        .into_keys()
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "lock or staging files left: {left:?}");
}

#[test]
fn a_planted_symbolic_link_is_never_followed() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let victim = d.path().join("victim.txt");
    std::fs::write(&victim, b"precious").unwrap();
    let problem = meshes().join("two_blocks.toml");
    // Links at every final name, and at the temporary names the former
    // writer used for this PID range: all are replaced or ignored.
    let mut planted = vec![];
    for n in [
        "two_blocks.vtu",
        "two_blocks_contact.vtu",
        "two_blocks.h5",
        "two_blocks.json",
    ] {
        planted.push(n.to_string());
    }
    for pid in 0..50u32 {
        for n in ["vtu", "h5", "json"] {
            planted.push(format!(
                ".two_blocks.{n}.tmp-{}-0",
                std::process::id() + pid
            ));
        }
    }
    for n in &planted {
        std::os::unix::fs::symlink(&victim, out.join(n)).unwrap();
    }
    let (code, log) = run(&[
        "solve",
        problem.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
    assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
    for n in [
        "two_blocks.vtu",
        "two_blocks_contact.vtu",
        "two_blocks.h5",
        "two_blocks.json",
    ] {
        let m = std::fs::symlink_metadata(out.join(n)).unwrap();
        assert!(m.file_type().is_file(), "{n} is not a regular file");
    }
    // A link at the lock's name: refused, nothing written through it.
    let out2 = d.path().join("out2");
    std::fs::create_dir(&out2).unwrap();
    std::os::unix::fs::symlink(&victim, out2.join(".two_blocks.lock")).unwrap();
    let (code, log) = run(&[
        "solve",
        problem.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
        "--quiet",
    ]);
    let line = assert_bad_input(code, &log, "lock is a link");
    assert!(line.contains("symbolic link"), "{line}");
    assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
}

/// A checkpoint of three_bodies_steps holding its first `k` steps, in `dir`.
fn partial_checkpoint(dir: &Path, k: usize) -> PathBuf {
    let steps = meshes().join("three_bodies_steps.toml");
    let (code, log) = run(&[
        "solve",
        steps.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--max-steps",
        &k.to_string(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
    dir.join("three_bodies_steps.h5")
}

#[test]
fn restart_refuses_a_checkpoint_of_another_problem() {
    let d = tempfile::tempdir().unwrap();
    let h5 = partial_checkpoint(&d.path().join("a"), 1);
    // The same mesh and counts, other loads: named in the message.
    let other = problem_copy(
        d.path(),
        "three_bodies_steps",
        &[("p = [0.0, -0.8e8]", "p = [0.0, -0.9e8]")],
    );
    let out = d.path().join("b");
    let (code, log) = run(&[
        "solve",
        other.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--restart",
        h5.to_str().unwrap(),
    ]);
    let line = assert_bad_input(code, &log, "other loads");
    assert!(
        line.contains("does not match") && line.contains("traction"),
        "{line}"
    );
    assert!(!out.join("three_bodies_steps.h5").exists());
    // Other steps.
    let other = problem_copy(
        d.path(),
        "three_bodies_steps",
        &[("displacement = 0.5", "displacement = 0.6")],
    );
    let (code, log) = run(&[
        "solve",
        other.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--restart",
        h5.to_str().unwrap(),
    ]);
    let line = assert_bad_input(code, &log, "other steps");
    assert!(line.contains("steps"), "{line}");
    // --no-contact changes the problem too.
    let steps = meshes().join("three_bodies_steps.toml");
    let (code, log) = run(&[
        "solve",
        steps.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-contact",
        "--restart",
        h5.to_str().unwrap(),
    ]);
    let line = assert_bad_input(code, &log, "--no-contact");
    assert!(line.contains("no_contact"), "{line}");
    // [solver] and [output] do not: the restart proceeds.
    let same = problem_copy(
        d.path(),
        "three_bodies_steps",
        &[
            ("tol = 1.0e-10", "tol = 1.0e-9"),
            ("[output]", "[output]\ncompress = true"),
        ],
    );
    let (code, log) = run(&[
        "solve",
        same.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--restart",
        h5.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
}

/// A checkpoint that another program holds open for writing (HDF5 locks it
/// with flock, as `File::lock` does here): the restart is refused as bad
/// input, naming the file and saying what the lock means.
#[test]
fn a_checkpoint_locked_by_another_program_is_named() {
    let d = tempfile::tempdir().unwrap();
    let good = partial_checkpoint(&d.path().join("a"), 1);
    let held = std::fs::File::open(&good).unwrap();
    held.lock().unwrap();
    let steps = meshes().join("three_bodies_steps.toml");
    let o = command()
        .env_remove("HDF5_USE_FILE_LOCKING")
        .args(["solve", steps.to_str().unwrap(), "--out"])
        .arg(d.path().join("b"))
        .arg("--restart")
        .arg(&good)
        .output()
        .unwrap();
    let (code, log) = joined(&o);
    let line = assert_bad_input(code, &log, "locked checkpoint");
    assert!(
        line.contains(good.to_str().unwrap()) && line.contains("open in another program"),
        "{line}"
    );
    assert!(!d.path().join("b").join("three_bodies_steps.h5").exists());
    drop(held);
}

/// A copy of the checkpoint `h5` of a run with load steps, with its mesh
/// and step files (the split layout of docs/problem-format.md §6), as
/// `dir/NAME.h5`.
fn copy_checkpoint(h5: &Path, dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let stem = h5.file_stem().unwrap().to_str().unwrap().to_string();
    for e in std::fs::read_dir(h5.parent().unwrap()).unwrap().flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        if n.starts_with(&stem) && n.ends_with(".h5") {
            std::fs::copy(e.path(), dir.join(&n)).unwrap();
        }
    }
    dir.join(h5.file_name().unwrap())
}

#[test]
fn crafted_checkpoints_are_refused_without_a_crash() {
    let d = tempfile::tempdir().unwrap();
    let good = partial_checkpoint(&d.path().join("a"), 1);
    let steps = meshes().join("three_bodies_steps.toml");
    let restart = |h5: &Path| {
        run(&[
            "solve",
            steps.to_str().unwrap(),
            "--out",
            d.path().join("b").to_str().unwrap(),
            "--restart",
            h5.to_str().unwrap(),
        ])
    };
    // A dataset declaring (1e11, 2) values in a small file: refused before
    // any allocation (it used to abort with a 1.6 TB allocation).
    let huge = copy_checkpoint(&good, &d.path().join("huge"));
    {
        let f = hdf5::File::open_rw(&huge).unwrap();
        let g = f.group("mesh").unwrap();
        g.unlink("nodes").unwrap();
        g.new_dataset::<f64>()
            .shape([100_000_000_000usize, 2])
            .create("nodes")
            .unwrap();
    }
    let (code, log) = restart(&huge);
    let line = assert_bad_input(code, &log, "huge dataset, restart");
    assert!(
        line.contains("/mesh/nodes") && line.contains("more bytes than the file"),
        "{line}"
    );
    let png = d.path().join("p.png");
    let (code, log) = run(&[
        "plot",
        huge.to_str().unwrap(),
        "--output",
        png.to_str().unwrap(),
    ]);
    assert_bad_input(code, &log, "huge dataset, plot");

    // A non-finite warm start.
    let nan = copy_checkpoint(&good, &d.path().join("nan"));
    {
        let f = hdf5::File::open_rw(&nan).unwrap();
        let ds = f.dataset("steps/0001/displacement").unwrap();
        let mut v = ds.read_raw::<f64>().unwrap();
        v[7] = f64::NAN;
        ds.write_raw(&v).unwrap();
    }
    let (code, log) = restart(&nan);
    let line = assert_bad_input(code, &log, "NaN warm start");
    assert!(line.contains("not finite"), "{line}");

    // No fingerprint (another program's file, or an older signorini's).
    let bare = copy_checkpoint(&good, &d.path().join("bare"));
    {
        let f = hdf5::File::open_rw(&bare).unwrap();
        f.delete_attr("fingerprint").unwrap();
    }
    let (code, log) = restart(&bare);
    let line = assert_bad_input(code, &log, "no fingerprint");
    assert!(line.contains("fingerprint"), "{line}");

    // The index of a split checkpoint copied without its files: refused,
    // saying that the directory moves as a whole.
    let alone = d.path().join("alone.h5");
    std::fs::copy(&good, &alone).unwrap();
    let (code, log) = restart(&alone);
    let line = assert_bad_input(code, &log, "index without its files");
    assert!(
        line.contains("alone.h5") && line.contains("as a whole"),
        "{line}"
    );

    // A directory and a FIFO.
    let (code, log) = restart(d.path());
    let line = assert_bad_input(code, &log, "directory");
    assert!(line.contains("is a directory"), "{line}");
}

#[test]
fn a_fifo_is_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("mesh.msh");
    let ok = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success();
    assert!(ok, "mkfifo failed");
    let toml = problem_copy(d.path(), "two_blocks", &[]);
    let text = std::fs::read_to_string(&toml).unwrap();
    let text = text.replace(
        meshes().join("two_blocks.msh").to_str().unwrap(),
        fifo.to_str().unwrap(),
    );
    std::fs::write(&toml, text).unwrap();
    let out = d.path().join("out");
    let (code, log) = run_with_deadline(
        &[
            "solve",
            toml.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        Duration::from_secs(60),
    );
    let line = assert_bad_input(code, &log, "FIFO mesh");
    assert!(line.contains("not a regular file"), "{line}");
    let (code, log) = run_with_deadline(
        &[
            "solve",
            meshes().join("two_blocks.toml").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--restart",
            fifo.to_str().unwrap(),
        ],
        Duration::from_secs(60),
    );
    let line = assert_bad_input(code, &log, "FIFO checkpoint");
    assert!(line.contains("not a regular file"), "{line}");
}

#[test]
fn a_run_that_fails_at_a_later_step_restores_the_previous_results() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let ok = problem_copy(d.path(), "three_bodies_steps", &[]);
    let (code, log) = run(&[
        "solve",
        ok.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
    let before = snapshot(&out);
    // Step 3 pulls the floating body away (unbounded): steps 1 and 2 are
    // committed, then the run fails.
    let bad = problem_copy(
        d.path(),
        "three_bodies_steps",
        &[(
            "t = 3.0\ndisplacement = 0.75\nload = 1.0",
            "t = 3.0\ndisplacement = 0.75\nload = -1.0",
        )],
    );
    let (code, log) = run(&[
        "solve",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(log.contains("step    2/4"), "step 2 was not solved:\n{log}");
    let line = assert_bad_input(code, &log, "step 3 unbounded");
    assert!(line.contains("unbounded"), "{line}");
    assert_eq!(
        snapshot(&out),
        before,
        "the previous results were not restored"
    );
}

#[test]
fn out_of_memory_is_exit_2_not_an_abort() {
    // A mesh file of 4 GiB (sparse: no disk used) read under a 1 GiB
    // address-space limit: the buffer for it cannot be allocated.
    let d = tempfile::tempdir().unwrap();
    let big = d.path().join("big.msh");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(4 << 30)
        .unwrap();
    let toml = problem_copy(d.path(), "two_blocks", &[]);
    let text = std::fs::read_to_string(&toml).unwrap();
    let text = text.replace(
        meshes().join("two_blocks.msh").to_str().unwrap(),
        big.to_str().unwrap(),
    );
    std::fs::write(&toml, text).unwrap();
    let o = Command::new("sh")
        .env("HDF5_USE_FILE_LOCKING", "FALSE")
        .arg("-c")
        .arg(format!(
            "ulimit -v 1048576 && exec {} solve {} --out {} --quiet",
            exe(),
            toml.display(),
            d.path().join("out").display()
        ))
        .output()
        .unwrap();
    let (code, log) = joined(&o);
    let line = assert_bad_input(code, &log, "ulimit -v");
    assert!(
        line.contains("out of memory") && line.contains("4.00 GiB"),
        "{line}"
    );
}

#[test]
fn messages_stay_one_short_line() {
    let d = tempfile::tempdir().unwrap();
    // A path with a newline: escaped, not a second line.
    let odd = d.path().join("two\nlines.toml");
    let (code, log) = run(&[
        "solve",
        odd.to_str().unwrap(),
        "--out",
        d.path().join("o").to_str().unwrap(),
    ]);
    let line = assert_bad_input(code, &log, "newline in the path");
    assert!(line.contains("two\\nlines.toml"), "{line}");
    // A 1 MB group name: cut with `…`, the line stays short.
    let long = "g".repeat(1 << 20);
    let toml = problem_copy(
        d.path(),
        "two_blocks",
        &[("on = \"top\"", &format!("on = \"{long}\""))],
    );
    let (code, log) = run(&[
        "solve",
        toml.to_str().unwrap(),
        "--out",
        d.path().join("o").to_str().unwrap(),
    ]);
    let line = assert_bad_input(code, &log, "1 MB name");
    assert!(
        line.contains('…') && line.len() < 1000,
        "{} bytes",
        line.len()
    );
}

// ------------------------------------------------------------ the lock file
//
// Issue 34: an existing `.NAME.lock` is never opened for writing (a hard
// link to a file elsewhere stays as it was), a fresh one is created with
// O_EXCL, and of an existing one at most a few bytes are read (a huge one
// names its holder at once instead of running out of memory).

/// `two_blocks` solved into `out` (created); (exit code, log).
fn solve_two_blocks(out: &Path) -> (i32, String) {
    let problem = meshes().join("two_blocks.toml");
    run_with_deadline(
        &[
            "solve",
            problem.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
        Duration::from_secs(120),
    )
}

/// The bytes, length and modification time of `p`.
fn fingerprint_of(p: &Path) -> (Vec<u8>, u64, std::time::SystemTime) {
    let m = std::fs::metadata(p).unwrap();
    (std::fs::read(p).unwrap(), m.len(), m.modified().unwrap())
}

#[test]
fn a_lock_hard_linked_to_a_file_elsewhere_is_never_written() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let victim = d.path().join("victim.txt");
    std::fs::write(&victim, b"precious contents, not a PID\n").unwrap();
    let was = fingerprint_of(&victim);
    std::fs::hard_link(&victim, out.join(".two_blocks.lock")).unwrap();
    // Nobody holds it: a stale lock; its name is replaced, the file kept.
    let (code, log) = solve_two_blocks(&out);
    assert_eq!(code, 0, "{log}");
    assert_eq!(fingerprint_of(&victim), was, "the linked file was written");
    assert!(!out.join(".two_blocks.lock").exists(), "lock left");
    assert!(out.join("two_blocks.json").is_file());
}

#[test]
fn a_held_lock_hard_linked_elsewhere_names_the_holder_and_stays_untouched() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let victim = d.path().join("victim.txt");
    std::fs::write(&victim, b"31337\n").unwrap();
    let held = std::fs::File::open(&victim).unwrap();
    held.try_lock().unwrap();
    let was = fingerprint_of(&victim);
    std::fs::hard_link(&victim, out.join(".two_blocks.lock")).unwrap();
    let (code, log) = solve_two_blocks(&out);
    let line = assert_bad_input(code, &log, "held hard-linked lock");
    assert!(line.contains("31337"), "{line}");
    assert_eq!(fingerprint_of(&victim), was);
    assert_eq!(
        snapshot(&out).into_keys().collect::<Vec<_>>(),
        vec![".two_blocks.lock"]
    );
    drop(held);
}

/// An 8 GiB sparse lock file starting with `head`, in a new `out` under `d`.
fn huge_lock(d: &Path, head: &[u8]) -> PathBuf {
    use std::io::Write;
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    let lock = out.join(".two_blocks.lock");
    let mut f = std::fs::File::create(&lock).unwrap();
    f.write_all(head).unwrap();
    f.set_len(8 << 30).unwrap();
    lock
}

/// `two_blocks` solved into `out` under a 2 GiB address-space limit (the
/// lock file must not be read whole); (exit code, log, seconds).
fn solve_two_blocks_limited(out: &Path) -> (i32, String, f64) {
    let t0 = Instant::now();
    let o = Command::new("timeout")
        .env("HDF5_USE_FILE_LOCKING", "FALSE")
        .args(["120", "sh", "-c"])
        .arg(format!(
            "ulimit -v 2097152 && exec {} solve {} --out {} --quiet",
            exe(),
            meshes().join("two_blocks.toml").display(),
            out.display()
        ))
        .output()
        .unwrap();
    let (code, log) = joined(&o);
    (code, log, t0.elapsed().as_secs_f64())
}

#[test]
fn a_huge_held_lock_file_names_its_holder_promptly() {
    let d = tempfile::tempdir().unwrap();
    let lock = huge_lock(d.path(), b"4242\n");
    let held = std::fs::File::open(&lock).unwrap();
    held.try_lock().unwrap();
    let (code, log, secs) = solve_two_blocks_limited(lock.parent().unwrap());
    let line = assert_bad_input(code, &log, "huge held lock");
    assert!(
        line.contains("process 4242") && !line.contains("out of memory"),
        "{line}"
    );
    assert!(secs < 60.0, "{secs} s");
    assert_eq!(std::fs::metadata(&lock).unwrap().len(), 8 << 30);
    drop(held);
}

#[test]
fn a_huge_stale_lock_file_is_replaced_promptly() {
    let d = tempfile::tempdir().unwrap();
    let lock = huge_lock(d.path(), b"999999999\n");
    let out = lock.parent().unwrap().to_path_buf();
    let (code, log, secs) = solve_two_blocks_limited(&out);
    assert_eq!(code, 0, "{log}");
    assert!(secs < 60.0, "{secs} s");
    assert!(!lock.exists(), "the stale lock is left");
}

#[test]
fn a_fifo_at_the_lock_name_is_refused_at_once_and_kept() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let fifo = out.join(".two_blocks.lock");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let (code, log) = solve_two_blocks(&out);
    let line = assert_bad_input(code, &log, "FIFO lock");
    assert!(line.contains("not a regular file"), "{line}");
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    assert_eq!(snapshot(&out).len(), 1, "the refused run wrote files");
}

#[test]
fn a_directory_at_the_lock_name_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir_all(out.join(".two_blocks.lock")).unwrap();
    std::fs::write(out.join(".two_blocks.lock").join("keep"), b"x").unwrap();
    let (code, log) = solve_two_blocks(&out);
    let line = assert_bad_input(code, &log, "directory lock");
    assert!(line.contains(".two_blocks.lock"), "{line}");
    assert_eq!(
        std::fs::read(out.join(".two_blocks.lock").join("keep")).unwrap(),
        b"x"
    );
}

#[test]
fn a_stale_lock_of_a_dead_run_is_taken_over_and_removed() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    // What a killed run leaves: its PID, no flock.
    std::fs::write(out.join(".two_blocks.lock"), b"999999\n").unwrap();
    let (code, log) = solve_two_blocks(&out);
    assert_eq!(code, 0, "{log}");
    let names: Vec<String> = snapshot(&out).into_keys().collect();
    assert!(!names.iter().any(|n| n.starts_with('.')), "{names:?}");
}

#[test]
fn a_lock_held_while_the_run_starts_is_never_truncated() {
    // The holder's file keeps its bytes: the refused run reads, never writes.
    use std::io::Write;
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let lock = out.join(".two_blocks.lock");
    let mut held = std::fs::File::create(&lock).unwrap();
    held.try_lock().unwrap();
    held.write_all(b"12345\nand more bytes after the PID\n")
        .unwrap();
    let was = fingerprint_of(&lock);
    let (code, log) = solve_two_blocks(&out);
    let line = assert_bad_input(code, &log, "held lock");
    assert!(line.contains("process 12345"), "{line}");
    assert_eq!(fingerprint_of(&lock), was);
    drop(held);
}
