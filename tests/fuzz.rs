//! Deterministic fuzzing of the input path: the shipped problems' `.msh` and
//! `.toml` files, mutated (byte flips, truncations, line deletions and
//! duplications, numbers replaced by huge / NaN / negative values, keys
//! deleted, values replaced, random characters), go through the whole
//! prepare path in memory: `mesh::gmsh::parse_msh`, `model::Problem::parse`,
//! `fem::build` (topology, conditions, assembly, semicoercive checks) and
//! `run::options`. No input may panic, and every error is one
//! non-empty line.
//!
//! `tests/mesh_reader.rs` already fuzzes the mesh reader alone on byte level;
//! this file adds the TOML side and the path from both to the QP.
//!
//! `SIGNORINI_FUZZ_CASES=N` sets the number of cases (default 3000),
//! `SIGNORINI_FUZZ_SEED=S` the seed (default fixed). A failing case is
//! written to a kept temporary directory, named in the failure message.

use signorini::mesh::{gmsh, Mesh};
use signorini::problem::Problem;
use signorini::qp::SolverSection;
use signorini::run;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod common;

use common::{root, XorShift};

const DEFAULT_CASES: usize = 3000;
const DEFAULT_SEED: u64 = 0x5167_6E6F_7269_6E69;

/// One shipped problem: its TOML, its mesh and the mesh's group names.
struct Sample {
    name: String,
    toml: String,
    msh: Vec<u8>,
    mesh: Mesh,
    groups: Vec<String>,
    /// Relative frequency (large meshes are slower to build).
    weight: usize,
}

fn sample(name: &str, toml: String, msh_path: &Path, weight: usize) -> Sample {
    let msh = std::fs::read(msh_path).unwrap();
    let mesh = gmsh::parse_msh(msh_path, &msh).unwrap();
    // The unmutated problem must build: otherwise the fuzzing starts from noise.
    let problem = Problem::parse(Path::new("fuzz.toml"), &toml).unwrap();
    signorini::fem::build(&mesh, &problem).unwrap_or_else(|e| panic!("{name}: {e}"));
    let groups = mesh.groups.iter().map(|g| g.name.clone()).collect();
    Sample {
        name: name.to_string(),
        toml,
        msh,
        mesh,
        groups,
        weight,
    }
}

fn corpus() -> Vec<Sample> {
    let square = "[mesh]\nfile = \"square.msh\"\n[materials.body_left]\nE = 1e9\nnu = 0.3\n\
        [materials.body_right]\nE = 1e9\nnu = 0.3\nrho = 1000.0\n[model]\ngravity = [0.0, -9.81]\n\
        [[dirichlet]]\non = \"bottom\"\nu = [0.0, 0.0]\n[[dirichlet]]\non = \"corner\"\nux = 0.0\n\
        [[traction]]\non = \"top\"\npn = -1e6\n[[force]]\non = \"corner\"\nf = [1.0, 0.0]\n\
        [[contact]]\non = \"interface\"\nnormals = \"segment\"\n[solver]\nmethod = \"cgc\"\ntol = 1e-8\n\
        [output]\nprobes = { a = [0.5, 0.5] }\n[[steps]]\nfactor = 0.5\n[[steps]]\nt = 3.0\n\
        dirichlet = { bottom = [0.0, -1e-3] }\n";
    let mut v = vec![];
    for f in [
        "square_ascii41",
        "square_bin41",
        "square_ascii22",
        "square_param_ascii41",
    ] {
        v.push(sample(
            f,
            square.to_string(),
            &root().join(format!("tests/data/msh/{f}.msh")),
            6,
        ));
    }
    for (name, msh, weight) in [
        ("two_blocks", "two_blocks", 4),
        ("two_blocks_glued", "two_blocks", 1),
        ("two_blocks_eccentric", "two_blocks_eccentric", 3),
        ("floating_block", "floating_block", 2),
        ("hertz", "hertz", 1),
        ("three_bodies_steps", "three_bodies", 1),
    ] {
        let toml = std::fs::read_to_string(root().join(format!("meshes/{name}.toml"))).unwrap();
        v.push(sample(
            name,
            toml,
            &root().join(format!("meshes/{msh}.msh")),
            weight,
        ));
    }
    v
}

// ---------------------------------------------------------------------------
// Mutations

/// Byte ranges of the lines of `b` (without the newline).
fn lines(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = vec![];
    let mut start = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            out.push((start, i));
            start = i + 1;
        }
    }
    if start < b.len() {
        out.push((start, b.len()));
    }
    out
}

/// Byte ranges of the whitespace-separated tokens of `b`.
fn tokens(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = vec![];
    let mut start = None;
    for (i, &c) in b.iter().enumerate() {
        match (c.is_ascii_whitespace(), start) {
            (true, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, b.len()));
    }
    out
}

const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "9",
    "15",
    "0.5",
    "1e-12",
    "1e-320",
    "1e308",
    "-1e308",
    "1e309",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967297",
    "2147483648",
    "-2147483649",
    "9223372036854775808",
    "99999999999999999999",
];

/// Byte range of the body of section `name` (`$Nodes` … `$EndNodes`).
fn section(b: &[u8], name: &str) -> Option<(usize, usize)> {
    let find = |pat: &[u8]| b.windows(pat.len()).position(|w| w == pat);
    let s = find(format!("${name}\n").as_bytes())? + name.len() + 2;
    let e = find(format!("$End{name}").as_bytes())?;
    (s < e).then_some((s, e))
}

/// Replaces a token of section `name` by another token of the same section
/// (keeps the file readable more often than random edits: moves a node onto
/// another's coordinate, or makes an element use another node).
fn swap_in_section(rng: &mut XorShift, b: &mut Vec<u8>, name: &str) -> String {
    let Some((s0, e0)) = section(b, name) else {
        return format!("no ${name}");
    };
    let ts: Vec<(usize, usize)> = tokens(&b[s0..e0])
        .into_iter()
        .map(|(s, e)| (s + s0, e + s0))
        .collect();
    if ts.len() < 2 {
        return format!("${name} too short");
    }
    let (s, e) = *rng.pick(&ts);
    let (s2, e2) = *rng.pick(&ts);
    let new = b[s2..e2].to_vec();
    let what = format!(
        "${name}: {} at {s} replaced by {}",
        String::from_utf8_lossy(&b[s..e]),
        String::from_utf8_lossy(&new)
    );
    b.splice(s..e, new);
    what
}

fn mutate_msh(rng: &mut XorShift, b: &mut Vec<u8>) -> String {
    if b.is_empty() {
        return "empty".into();
    }
    match rng.below(12) {
        8 | 9 => swap_in_section(rng, b, "Nodes"),
        10 | 11 => swap_in_section(rng, b, "Elements"),
        0 => {
            let at = rng.below(b.len());
            b[at] = rng.next() as u8;
            format!("byte {at} flipped")
        }
        1 => {
            let len = rng.below(b.len());
            b.truncate(len);
            format!("truncated to {len}")
        }
        2 | 3 => {
            let ls = lines(b);
            let (s, e) = *rng.pick(&ls);
            if rng.below(2) == 0 {
                b.drain(s..(e + 1).min(b.len()));
                format!("line at {s} deleted")
            } else {
                let line: Vec<u8> = b[s..(e + 1).min(b.len())].to_vec();
                b.splice(s..s, line);
                format!("line at {s} duplicated")
            }
        }
        4 | 5 => {
            // A number replaced: by an extreme value or by another token of the file.
            let ts = tokens(b);
            for _ in 0..8 {
                let (s, e) = *rng.pick(&ts);
                let t = &b[s..e];
                if std::str::from_utf8(t)
                    .ok()
                    .and_then(|t| t.parse::<f64>().ok())
                    .is_none()
                {
                    continue;
                }
                let new: Vec<u8> = if rng.below(3) == 0 {
                    let (s2, e2) = *rng.pick(&ts);
                    b[s2..e2].to_vec()
                } else {
                    rng.pick(NUMBERS).as_bytes().to_vec()
                };
                let what = format!(
                    "number {} at {s} replaced by {}",
                    String::from_utf8_lossy(t),
                    String::from_utf8_lossy(&new)
                );
                b.splice(s..e, new);
                return what;
            }
            "no number found".into()
        }
        6 => {
            let ls = lines(b);
            let (a, b2) = (rng.below(ls.len()), rng.below(ls.len()));
            let (i, j) = (a.min(b2), a.max(b2));
            if i == j {
                return "swap of a line with itself".into();
            }
            let (li, lj) = (ls[i], ls[j]);
            let mut out = b[..li.0].to_vec();
            out.extend_from_slice(&b[lj.0..lj.1]);
            out.extend_from_slice(&b[li.1..lj.0]);
            out.extend_from_slice(&b[li.0..li.1]);
            out.extend_from_slice(&b[lj.1..]);
            *b = out;
            format!("lines at {} and {} swapped", li.0, lj.0)
        }
        _ => {
            let at = rng.below(b.len() + 1);
            let n = 1 + rng.below(16);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            b.splice(at..at, bytes);
            format!("{n} random bytes inserted at {at}")
        }
    }
}

const VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "0.5",
    "0.49999999",
    "-0.999999",
    "2",
    "-0.0",
    "1e-320",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-inf",
    "18446744073709551616",
    "\"\"",
    "\"x\"",
    "\"magic\"",
    "\"segment\"",
    "\"averaged\"",
    "\"stress\"",
    "\"single\"",
    "\"none\"",
    "\"ssn\"",
    "\"asm\"",
    "[]",
    "[0.0]",
    "[1.0, 2.0]",
    "[nan, 0.0]",
    "[1e308, -1e308]",
    "[0.0, 0.0, 0.0]",
    "{}",
    "{ a = [0.0, 0.0] }",
    "{ bottom = [0.0, 1.0] }",
    "true",
];

const HEADERS: &[&str] = &[
    "[[contact]]",
    "[[dirichlet]]",
    "[[traction]]",
    "[[slip]]",
    "[[force]]",
    "[[steps]]",
    "[solver]",
    "[model]",
    "[output]",
    "[mesh]",
    "[materials.x]",
    "[materials]",
    "[[materials]]",
];

const CHARS: &[&str] = &[
    "=", "[", "]", "{", "}", "\"", "'", ",", "#", "\n", "\r\n", " ", "\t", ".", "-", "ν", "é",
    "\u{feff}", "\0", "\\", "\"\"\"", "a", "1", "e",
];

fn mutate_toml(rng: &mut XorShift, t: &mut String, groups: &[String]) -> String {
    let ls = lines(t.as_bytes());
    match rng.below(11) {
        0 if !ls.is_empty() => {
            let (s, e) = *rng.pick(&ls);
            let line = t[s..e].to_string();
            t.replace_range(s..(e + 1).min(t.len()), "");
            format!("line {line:?} deleted")
        }
        1 if !ls.is_empty() => {
            let (s, e) = *rng.pick(&ls);
            let line = t[s..(e + 1).min(t.len())].to_string();
            t.insert_str(s, &line);
            format!("line {:?} duplicated", line.trim_end())
        }
        2..=4 => {
            // The value of a `key = value` line replaced.
            let kv: Vec<(usize, usize)> = ls
                .iter()
                .copied()
                .filter(|&(s, e)| t[s..e].contains('=') && !t[s..e].trim_start().starts_with('#'))
                .collect();
            if kv.is_empty() {
                return "no key".into();
            }
            let (s, e) = *rng.pick(&kv);
            let eq = s + t[s..e].find('=').unwrap_or(0);
            let old = t[eq + 1..e].trim();
            // Half of the time a value of the same kind (so that parsing goes on).
            let v = if rng.below(2) == 0 && old.parse::<f64>().is_ok() {
                rng.pick(NUMBERS).to_string()
            } else if rng.below(2) == 0 && old.starts_with('[') {
                format!("[{}, {}]", rng.pick(NUMBERS), rng.pick(NUMBERS))
            } else if rng.below(4) == 0 && !groups.is_empty() {
                format!("\"{}\"", rng.pick(groups))
            } else {
                rng.pick(VALUES).to_string()
            };
            let what = format!("{:?} → value {v}", &t[s..e]);
            t.replace_range(eq + 1..e, &format!(" {v}"));
            what
        }
        5 => {
            let h = *rng.pick(HEADERS);
            let at = ls.get(rng.below(ls.len() + 1)).map_or(t.len(), |l| l.0);
            t.insert_str(at, &format!("{h}\n"));
            format!("header {h} inserted")
        }
        6 => {
            // Random characters at a character boundary.
            let mut at = rng.below(t.len() + 1);
            while !t.is_char_boundary(at) {
                at -= 1;
            }
            let n = 1 + rng.below(4);
            let s: String = (0..n).map(|_| *rng.pick(CHARS)).collect();
            t.insert_str(at, &s);
            format!("{s:?} inserted at {at}")
        }
        7 => {
            let mut at = rng.below(t.len() + 1);
            while !t.is_char_boundary(at) {
                at -= 1;
            }
            t.truncate(at);
            format!("truncated to {at}")
        }
        _ => {
            // A quoted name replaced by another group name (or a foreign one).
            let quotes: Vec<usize> = t.match_indices('"').map(|(i, _)| i).collect();
            if quotes.len() < 2 {
                return "no string".into();
            }
            let k = rng.below(quotes.len() / 2) * 2;
            let (a, b) = (quotes[k], quotes[k + 1]);
            let name = if groups.is_empty() || rng.below(5) == 0 {
                "nowhere".to_string()
            } else {
                rng.pick(groups).clone()
            };
            let what = format!("{:?} → {name:?}", &t[a + 1..b]);
            t.replace_range(a + 1..b, &name);
            what
        }
    }
}

// ---------------------------------------------------------------------------
// The path under test

#[derive(Default)]
struct Tally {
    mesh_err: usize,
    toml_err: usize,
    build_err: usize,
    built: usize,
}

/// Error messages are one non-empty line.
fn check_message(stage: &str, msg: String) -> Result<(), String> {
    if msg.trim().is_empty() || msg.contains('\n') {
        Err(format!("{stage}: the message is not one line: {msg:?}"))
    } else {
        Ok(())
    }
}

fn run_case(
    msh: &[u8],
    toml: &str,
    mesh0: &Mesh,
    mesh_mutated: bool,
    tally: &mut Tally,
) -> Result<(), String> {
    let mesh_path = Path::new("fuzz.msh");
    let owned;
    let mesh = if mesh_mutated {
        match gmsh::parse_msh(mesh_path, msh) {
            Ok(m) => {
                owned = m;
                &owned
            }
            Err(e) => {
                tally.mesh_err += 1;
                return check_message("mesh", e.to_string());
            }
        }
    } else {
        mesh0
    };
    let problem = match Problem::parse(Path::new("fuzz.toml"), toml) {
        Ok(p) => p,
        Err(e) => {
            tally.toml_err += 1;
            return check_message("toml", e.to_string());
        }
    };
    let _ = run::options(&problem, &SolverSection::default()).map_err(|e| e.to_string());
    match signorini::fem::build(mesh, &problem) {
        Ok(model) => {
            tally.built += 1;
            // Load steps rebuild the model with scaled data.
            for s in 0..problem.file.nsteps().min(3) {
                let mut p = problem.clone();
                p.file = problem.file.at_step(s);
                if let Err(e) = signorini::fem::build(mesh, &p) {
                    check_message("step build", e.to_string())?;
                }
            }
            let n = model.qp.n();
            if model.qp.c.nrows != n || model.qp.a.ncols != n || model.qp.a.nrows != model.qp.m() {
                return Err("inconsistent QP dimensions".into());
            }
            Ok(())
        }
        Err(e) => {
            tally.build_err += 1;
            check_message("build", e.to_string())
        }
    }
}

#[test]
fn mutated_meshes_and_problem_files_never_panic() {
    let cases: usize = std::env::var("SIGNORINI_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(DEFAULT_CASES);
    let seed: u64 = std::env::var("SIGNORINI_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(DEFAULT_SEED);
    let corpus = corpus();
    let wsum: usize = corpus.iter().map(|s| s.weight).sum();
    let t0 = Instant::now();
    let mut tally = Tally::default();
    let mut failures: Vec<String> = vec![];
    let mut keep_dir: Option<PathBuf> = None;
    // Silence the default hook's report of every caught panic; count them instead.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    for case in 0..cases {
        let mut rng = XorShift::seeded(seed ^ (case as u64).wrapping_mul(0x2545_F491_4F6C_DD1D));
        let mut w = rng.below(wsum);
        let s = corpus
            .iter()
            .find(|s| {
                if w < s.weight {
                    true
                } else {
                    w -= s.weight;
                    false
                }
            })
            .unwrap();
        // 0: TOML only (half of the cases), 1: mesh only, 2: both.
        let mode = [0, 0, 1, 2][rng.below(4)];
        let mut msh = s.msh.clone();
        let mut toml = s.toml.clone();
        let mut what = vec![];
        for _ in 0..[1, 1, 1, 2, 3][rng.below(5)] {
            if mode != 1 {
                what.push(format!(
                    "toml: {}",
                    mutate_toml(&mut rng, &mut toml, &s.groups)
                ));
            }
            if mode != 0 {
                what.push(format!("msh: {}", mutate_msh(&mut rng, &mut msh)));
            }
        }
        let r = catch_unwind(AssertUnwindSafe(|| {
            let mut t = Tally::default();
            let r = run_case(&msh, &toml, &s.mesh, mode != 0, &mut t);
            (r, t)
        }));
        let problem = match r {
            Ok((Ok(()), t)) => {
                tally.mesh_err += t.mesh_err;
                tally.toml_err += t.toml_err;
                tally.build_err += t.build_err;
                tally.built += t.built;
                None
            }
            Ok((Err(msg), _)) => Some(msg),
            Err(p) => Some(format!(
                "PANIC: {}",
                p.downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()
            )),
        };
        if let Some(msg) = problem {
            if failures.len() < 10 {
                let dir = keep_dir.get_or_insert_with(|| {
                    tempfile::Builder::new()
                        .prefix("signorini-fuzz-")
                        .tempdir()
                        .unwrap()
                        .keep()
                });
                std::fs::write(dir.join(format!("case{case}.msh")), &msh).unwrap();
                std::fs::write(dir.join(format!("case{case}.toml")), &toml).unwrap();
            }
            failures.push(format!(
                "case {case} ({}; {}): {msg}",
                s.name,
                what.join("; ")
            ));
        }
    }
    std::panic::set_hook(default_hook);
    let dt = t0.elapsed().as_secs_f64();
    eprintln!(
        "fuzz: {cases} cases in {dt:.1} s (seed {seed}): {} mesh errors, {} TOML errors, \
         {} build errors, {} built, {} failures",
        tally.mesh_err,
        tally.toml_err,
        tally.build_err,
        tally.built,
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {cases} cases failed (inputs of the first ones in {}):\n{}",
        failures.len(),
        keep_dir
            .map(|d| d.display().to_string())
            .unwrap_or_default(),
        failures
            .iter()
            .take(20)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}
