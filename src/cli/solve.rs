//! `signorini solve`: one problem, one method, all outputs and the report.

use super::{SolveArgs, SolverFlags};
use crate::io::atomic::{self, OutputLock, Stage};
use crate::pipeline::{self, Prepared, SolverChoice};
use crate::post;
use crate::qp::{registry, QpResult};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const EXIT_BAD_INPUT: i32 = 2;
pub const EXIT_NOT_CONVERGED: i32 = 3;

pub fn choice(f: &SolverFlags) -> SolverChoice {
    SolverChoice {
        method: f.method.clone(),
        preconditioner: f.preconditioner.clone(),
        tol: f.tol,
        max_iter: f.max_iter,
        omega: f.omega,
        release: f.release.clone(),
    }
}

/// The prefix of the staging directories of the problem `name`.
fn stage_prefix(name: &str) -> String {
    format!("{}{name}-", crate::io::atomic::STAGE_PREFIX)
}

/// The file name of an output path.
fn fname(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Checks of a restart checkpoint before its steps are trusted: the same
/// problem (fingerprint), the same mesh sizes, and a plausible warm start.
fn check_restart(
    rp: &Path,
    ck: &crate::io::hdf5::Checkpoint,
    fingerprint: &str,
    om: &crate::io::OutMesh,
    problem: &Path,
) -> Result<(), String> {
    let shown = rp.display();
    let Some((_, theirs)) = ck.attrs.iter().find(|(k, _)| k == "fingerprint") else {
        return Err(format!(
            "{shown}: the checkpoint has no problem fingerprint (written by another program or an older signorini), so it cannot be matched to {}; solve from the start",
            problem.display()
        ));
    };
    let diff = pipeline::fingerprint_diff(theirs, fingerprint);
    if !diff.is_empty() {
        return Err(format!(
            "{shown}: the checkpoint does not match {}: it was written for a different {} (restart needs the same mesh and the same loads, materials, contacts and steps)",
            problem.display(),
            diff.join(", ")
        ));
    }
    if ck.mesh.points.len() != om.points.len() || ck.mesh.triangles.len() != om.triangles.len() {
        return Err(format!(
            "{shown}: checkpoint mesh ({} points, {} triangles) does not match {} ({} points, {} triangles)",
            ck.mesh.points.len(),
            ck.mesh.triangles.len(),
            problem.display(),
            om.points.len(),
            om.triangles.len()
        ));
    }
    // A warm start beyond 10³ mesh diagonals is no displacement this
    // problem produced: refuse it rather than start the solver from it.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &om.points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    for (k, st) in ck.steps.iter().enumerate() {
        let umax = st
            .displacement
            .iter()
            .fold(0.0f64, |m, u| m.max(u[0].abs().max(u[1].abs())));
        let finite = st
            .displacement
            .iter()
            .all(|u| u[0].is_finite() && u[1].is_finite());
        let plausible = umax <= 1e3 * diag;
        if !finite || !plausible {
            return Err(format!(
                "{shown}: step {} holds displacements that are not finite or implausibly large (max |u| = {umax:e}, mesh size {diag:e}); it cannot be a warm start",
                k + 1
            ));
        }
    }
    Ok(())
}

pub fn run(a: &SolveArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let t0 = Instant::now();
    let target = a.solver.kkt_target;
    if !(target > 0.0 && target.is_finite()) {
        return bad_input(&format!(
            "--kkt-target {target}: the KKT target must be a positive number"
        ));
    }
    if a.max_steps == Some(0) {
        return bad_input(&"--max-steps 0: load steps count from 1");
    }
    let prep = match pipeline::prepare_with(&a.problem, a.no_contact, build) {
        Ok(p) => p,
        Err(e) => return bad_input(&e),
    };
    let (method, opts) = match pipeline::options(&prep.problem, &choice(&a.solver)) {
        Ok(x) => x,
        Err(e) => return bad_input(&e),
    };
    let mut opts = opts;
    opts.progress = !quiet;
    let dir = a
        .out
        .clone()
        .or(prep.problem.file.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    // Fail on an unwritable output directory before spending time solving.
    if let Err(e) = std::fs::create_dir_all(&dir) {
        return bad_input(&format!(
            "{}: cannot create output directory: {e}",
            dir.display()
        ));
    }
    let name = prep.problem.name.clone();
    // One run per output name at a time; released (and its file removed)
    // when `_lock` drops, after the last output is in place.
    let _lock = match OutputLock::acquire(&dir, &name) {
        Ok(l) => l,
        Err(msg) => return bad_input(&msg),
    };
    atomic::remove_stale_stages(&dir, &stage_prefix(&name));
    // Every file of the run is written here and moved into place by commits;
    // an error (an early return) drops the stage, which puts the previous
    // files back.
    let mut stage = match Stage::new(&dir, &stage_prefix(&name)) {
        Ok(s) => s,
        Err(e) => return bad_input(&e),
    };
    let sdir = stage.dir().to_path_buf();
    // Errors name the final file, not its staged copy.
    let fail = |e: &dyn std::fmt::Display| -> i32 {
        let msg = e.to_string().replace(
            &format!("{}/", sdir.display()),
            &format!("{}/", dir.display()),
        );
        bad_input(&msg)
    };
    let file = &prep.problem.file;
    let multi = !file.steps.is_empty();
    let nsteps = file.nsteps();
    let last = a.max_steps.unwrap_or(nsteps).min(nsteps);
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let fingerprint = pipeline::fingerprint(&prep, a.no_contact);
    let h5_name = fname(&pipeline::output_paths(&dir, &name, None).h5);
    let staged_h5 = stage.path(&h5_name);
    let compress = a.compress || file.output.compress;

    // Restart: the steps already in the checkpoint are kept; warm start from the last.
    let mut first = 0usize;
    let mut u_prev: Option<Vec<[f64; 2]>> = None;
    // The checkpoint the next step extends (None: a new one).
    let mut base: Option<PathBuf> = None;
    if let Some(rp) = &a.restart {
        let ck = match crate::io::hdf5::read_checkpoint(rp) {
            Ok(c) => c,
            Err(e) => return bad_input(&format!("--restart: {e}")),
        };
        if let Err(msg) = check_restart(rp, &ck, &fingerprint, &om, &a.problem) {
            return bad_input(&msg);
        }
        first = ck.steps.len();
        u_prev = ck.steps.last().map(|s| s.displacement.clone());
        base = Some(rp.clone());
        if !quiet {
            println!(
                "restart     from step {first} of {} ({})",
                nsteps,
                rp.display()
            );
        }
    }
    if first >= last {
        // Nothing to solve; a checkpoint restarted from elsewhere is still
        // copied to the output directory, as a run would have left it.
        if let Some(rp) = &base {
            if rp.canonicalize().ok() != stage.target(&h5_name).canonicalize().ok() {
                if let Err(e) = std::fs::copy(rp, &staged_h5) {
                    return fail(&format!(
                        "{}: cannot copy the checkpoint: {e}",
                        rp.display()
                    ));
                }
                if let Err(e) = stage.commit(&[&h5_name]) {
                    return fail(&e);
                }
            }
        }
        stage.finish();
        if !quiet {
            if first >= nsteps {
                println!("nothing to do: the checkpoint already holds all {nsteps} steps");
            } else {
                println!(
                    "nothing to do: the checkpoint already holds {first} steps (--max-steps {last})"
                );
            }
        }
        return 0;
    }

    let mut code = 0;
    let mut step_rows = vec![];
    let mut final_state = None;
    for s in first..last {
        let ts = Instant::now();
        // Without [[steps]] the prepared model is the problem; with steps every
        // step (the first included) gets its own loads.
        let model = if !multi {
            None
        } else {
            match pipeline::step_model(&prep, s) {
                Ok(m) => Some(m),
                Err(e) => return bad_input(&e),
            }
        };
        let model_ref = model.as_ref().unwrap_or(&prep.model);
        let t_assemble = if model.is_none() {
            prep.t_assemble
        } else {
            ts.elapsed().as_secs_f64()
        };
        let mut o = opts.clone();
        o.x0 = u_prev.as_ref().map(|u| pipeline::reduce(model_ref, u));
        let t_solve0 = Instant::now();
        let res = match pipeline::solve_model(&prep, model_ref, &method, &o) {
            Ok(r) => r,
            Err(e) => return bad_input(&e),
        };
        let t_solve = t_solve0.elapsed().as_secs_f64();
        let t_w = Instant::now();
        let out = pipeline::output_paths(&dir, &name, multi.then_some(s + 1));
        let staged = pipeline::output_paths(&sdir, &name, multi.then_some(s + 1));
        let mut problem_s = prep.problem.clone();
        problem_s.file = file.at_step(s);
        let (mut step, forces) =
            post::step_output_with_forces(model_ref, &problem_s, &res, file.step_time(s));
        step.info.method = method.clone();
        step.info.preconditioner = preconditioner_label(&method, &opts);
        step.info.time_assemble = t_assemble;
        step.info.time_solve = t_solve;
        step.info.time_total = ts.elapsed().as_secs_f64();
        // The staged checkpoint: a copy of the one this step extends, or new.
        if !staged_h5.exists() {
            let made = match &base {
                Some(b) => std::fs::copy(b, &staged_h5)
                    .map(|_| ())
                    .map_err(|e| format!("{}: cannot copy the checkpoint: {e}", b.display())),
                None => pipeline::create_checkpoint(&prep, &staged_h5, &om, &fingerprint)
                    .map_err(|e| e.to_string()),
            };
            if let Err(msg) = made {
                return fail(&msg);
            }
        }
        if let Err(e) = pipeline::write_step(&staged, &om, &step, s + 1, compress) {
            return fail(&e);
        }
        let pvd_name = format!("{name}.pvd");
        if multi {
            let entries: Vec<(f64, String)> = (0..=s)
                .flat_map(|k| {
                    let o = pipeline::output_paths(&dir, &name, Some(k + 1));
                    [
                        (file.step_time(k), fname(&o.vtu)),
                        (file.step_time(k), fname(&o.contact_vtu)),
                    ]
                })
                .collect();
            if let Err(e) = crate::io::vtu::write_pvd(&stage.path(&pvd_name), &entries) {
                return fail(&e);
            }
            // A load step is one commit: its VTU pair, the time series and
            // the checkpoint grown by this step.
            let names = [
                fname(&out.vtu),
                fname(&out.contact_vtu),
                pvd_name.clone(),
                h5_name.clone(),
            ];
            let names: Vec<&str> = names.iter().map(String::as_str).collect();
            if let Err(e) = stage.commit(&names) {
                return fail(&e);
            }
            base = Some(out.h5.clone());
        }
        let t_write = t_w.elapsed().as_secs_f64();
        if multi && !quiet {
            println!(
                "step {:>4}/{}  t = {:<10} {} in {} iterations, KKT {:.2e}, {} active, {:.3} s",
                s + 1,
                nsteps,
                file.step_time(s),
                if res.status.converged() {
                    "converged"
                } else {
                    "NOT CONVERGED"
                },
                res.iterations,
                res.kkt.max(),
                res.active.iter().filter(|a| **a).count(),
                ts.elapsed().as_secs_f64()
            );
        }
        step_rows.push(json!({
            "step": s + 1, "t": file.step_time(s), "converged": res.status.converged(),
            "iterations": res.iterations, "kkt_max": res.kkt.max(), "energy": res.energy,
            "active": res.active.iter().filter(|a| **a).count(),
        }));
        if !res.status.converged() {
            eprintln!(
                "warning: step {}: {} did not converge: {} (outputs written and flagged converged = false)",
                s + 1,
                method,
                res.status.describe()
            );
            code = EXIT_NOT_CONVERGED;
        } else if !registry::certified(&method, &res.kkt, a.solver.kkt_target, a.solver.strict) {
            eprintln!(
                "warning: step {}: not certified: KKT residual {:.2e} above the target {:.0e} (outputs written and flagged certified = false; docs/methods.md §8)",
                s + 1,
                res.kkt.max(),
                a.solver.kkt_target
            );
            code = EXIT_NOT_CONVERGED;
        } else if !res.kkt.within(a.solver.kkt_target) {
            // Penalty, certified against its own penalised problem.
            eprintln!(
                "warning: step {}: {method} violates the contact conditions by O(ε_p) (KKT of the unpenalised problem {:.2e}; --strict certifies against it)",
                s + 1,
                res.kkt.max()
            );
        }
        u_prev = Some(step.displacement.clone());
        let timings = Timings {
            read: prep.t_read,
            assemble: t_assemble,
            solve: t_solve,
            write: t_write,
            total: 0.0,
        };
        final_state = Some((model, res, step, forces, out, timings));
    }
    let Some((model, res, step, forces, out, mut timings)) = final_state else {
        // Unreachable: first < last, so the loop ran at least once.
        return bad_input(&"no load step was solved");
    };
    timings.total = t0.elapsed().as_secs_f64();
    let model_ref = model.as_ref().unwrap_or(&prep.model);
    let certified = res.status.converged()
        && registry::certified(&method, &res.kkt, a.solver.kkt_target, a.solver.strict);
    let mut summary = summary_json(
        &prep,
        model_ref,
        &res,
        &method,
        &step.info.preconditioner,
        &step,
        &forces,
        &timings,
        certified,
        a.solver.kkt_target,
    );
    if multi {
        summary["steps"] = json!(step_rows);
    }
    let text = match serde_json::to_string_pretty(&summary) {
        Ok(t) => t,
        Err(e) => return bad_input(&format!("JSON summary: {e}")),
    };
    let json_name = fname(&out.json);
    if let Err(e) = crate::io::atomic::write_atomic_bytes(&stage.path(&json_name), text.as_bytes())
    {
        return fail(&e);
    }
    // The last commit: the JSON summary (the commit record) and, for a
    // single solve, every other file with it.
    let names = if multi {
        vec![json_name]
    } else {
        vec![
            fname(&out.vtu),
            fname(&out.contact_vtu),
            h5_name.clone(),
            json_name,
        ]
    };
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    if let Err(e) = stage.commit(&names) {
        return fail(&e);
    }
    stage.finish();
    if !quiet {
        print_report(
            &prep,
            model_ref,
            &res,
            &method,
            &step,
            &summary,
            &timings,
            &out,
            a.solver.kkt_target,
        );
    }
    code
}

pub fn preconditioner_label(method: &str, opts: &crate::qp::SolveOptions) -> String {
    match crate::qp::registry::find(method) {
        Some(m) if m.preconditioned => opts.preconditioner.name().to_string(),
        _ => "-".to_string(),
    }
}

/// Print the one error line of bad input; the exit code for it.
pub(crate) fn bad_input(e: &impl std::fmt::Display) -> i32 {
    eprintln!("error: {}", one_line(&e.to_string()));
    EXIT_BAD_INPUT
}

/// Longest error line printed (a longer one is cut with `…`).
const MAX_LINE: usize = 2000;

/// A message as one line: control characters (a newline in a path) are
/// escaped, and an overlong message (a huge name) is cut.
pub(crate) fn one_line(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len().min(MAX_LINE + 16));
    for (n, c) in msg.chars().enumerate() {
        if n >= MAX_LINE {
            out.push('…');
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

pub struct Timings {
    pub read: f64,
    pub assemble: f64,
    pub solve: f64,
    pub write: f64,
    pub total: f64,
}

#[allow(clippy::too_many_arguments)]
pub fn summary_json(
    prep: &Prepared,
    m: &crate::fem::Model,
    res: &QpResult,
    method: &str,
    pc: &str,
    step: &crate::io::StepOutput,
    fo: &post::forces::Forces,
    t: &Timings,
    certified: bool,
    target: f64,
) -> serde_json::Value {
    let mut probes = serde_json::Map::new();
    for (name, x, node, u) in pipeline::probes(prep, &step.displacement) {
        probes.insert(name, json!({ "x": x[0], "y": x[1], "node": node, "tag": prep.mesh.node_tags[m.topo.point_node[node]], "u": u }));
    }
    let max_p = step.contact_pressure.iter().fold(0.0f64, |a, b| a.max(*b));
    let total: f64 = step.multipliers.iter().sum();
    let reactions: serde_json::Map<String, serde_json::Value> =
        fo.groups.iter().map(|g| (g.on.clone(), json!(g))).collect();
    let interfaces: serde_json::Map<String, serde_json::Value> = fo
        .interfaces
        .iter()
        .map(|i| (i.name.clone(), json!(i)))
        .collect();
    json!({
        "problem": prep.problem.name,
        "method": method,
        "preconditioner": pc,
        "converged": res.status.converged(),
        "status": res.status.describe(),
        "iterations": res.iterations,
        "inner_iterations": res.inner_iterations,
        "nodes": m.topo.points.len(),
        "mesh_nodes": prep.mesh.nodes.len(),
        "triangles": m.topo.triangles.len(),
        "bodies": m.topo.nbodies,
        "rigid_modes": m.qp.kernel.len(),
        "dofs": m.qp.n(),
        "constraints": m.qp.m(),
        "active": res.active.iter().filter(|a| **a).count(),
        "energy": res.energy,
        "strain_energy": fo.strain_energy,
        "load_work": fo.load_work,
        "kkt": {
            "primal": res.kkt.primal,
            "dual": res.kkt.dual,
            "complementarity": res.kkt.complementarity,
            "stationarity": res.kkt.stationarity,
            "contact_balance": res.kkt.contact_balance,
            "target": target,
            "certified": certified,
        },
        "contact": { "max_pressure": max_p, "total_force": total, "interfaces": interfaces },
        "loads": fo.loads,
        "reactions": reactions,
        "notes": res.notes,
        "probes": probes,
        "timings_s": {
            "read": t.read,
            "assemble": t.assemble,
            "solve": t.solve,
            "write": t.write,
            "total": t.total,
            "phases": res.timings.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        },
    })
}

#[allow(clippy::too_many_arguments)]
fn print_report(
    prep: &Prepared,
    m: &crate::fem::Model,
    res: &QpResult,
    method: &str,
    step: &crate::io::StepOutput,
    summary: &serde_json::Value,
    t: &Timings,
    out: &pipeline::Outputs,
    target: f64,
) {
    println!(
        "signorini {} — {} ({})",
        env!("CARGO_PKG_VERSION"),
        prep.problem.name,
        prep.problem.path.display()
    );
    let floating: Vec<String> = {
        let mut b: Vec<u32> = m.kernel_body.clone();
        b.dedup();
        b.iter().map(|&b| m.body_label(b as usize)).collect()
    };
    println!(
        "mesh        {} nodes ({} with interface copies), {} triangles, {} bodies{}",
        prep.mesh.nodes.len(),
        m.topo.points.len(),
        m.topo.triangles.len(),
        m.topo.nbodies,
        if floating.is_empty() {
            String::new()
        } else {
            format!(
                "; semicoercive: {} ({} rigid modes)",
                floating.join(", "),
                m.qp.kernel.len()
            )
        }
    );
    println!(
        "problem     {} DOFs, {} contact constraints",
        m.qp.n(),
        m.qp.m()
    );
    println!(
        "method      {method} (preconditioner {})",
        step.info.preconditioner
    );
    println!(
        "status      {} after {} iterations ({} inner)",
        res.status.describe(),
        res.iterations,
        res.inner_iterations
    );
    let k = &res.kkt;
    println!(
        "KKT         primal {:.2e}  dual {:.2e}  complementarity {:.2e}  stationarity {:.2e}  contact balance {:.2e}  → {}",
        k.primal,
        k.dual,
        k.complementarity,
        k.stationarity,
        k.contact_balance,
        if summary["kkt"]["certified"] == true {
            format!("certified (≤ {target:.0e})")
        } else {
            format!("NOT certified (target {target:.0e})")
        }
    );
    println!(
        "energy      {:.6e} (QP objective); strain energy {:.6e}, work of the loads {:.6e}",
        res.energy,
        summary["strain_energy"].as_f64().unwrap_or(f64::NAN),
        summary["load_work"].as_f64().unwrap_or(f64::NAN)
    );
    println!(
        "contact     {} active of {}, max pressure {:.4e}, total force {:.4e}",
        summary["active"],
        m.qp.m(),
        summary["contact"]["max_pressure"].as_f64().unwrap_or(0.0),
        summary["contact"]["total_force"].as_f64().unwrap_or(0.0)
    );
    // Global balance: loads + reactions = 0 (contact forces are internal).
    let res2 = |v: &serde_json::Value| -> ([f64; 2], f64) {
        let f = |k: usize| v["force"][k].as_f64().unwrap_or(f64::NAN);
        ([f(0), f(1)], v["moment"].as_f64().unwrap_or(f64::NAN))
    };
    let (lf, lm) = res2(&summary["loads"]);
    let mut rf = [0.0, 0.0];
    let mut rm = 0.0;
    if let Some(groups) = summary["reactions"].as_object() {
        for (name, g) in groups {
            let (f, mo) = res2(g);
            rf = [rf[0] + f[0], rf[1] + f[1]];
            rm += mo;
            println!(
                "reaction    {:<14} ({}) F = ({:.4e}, {:.4e}), M = {:.4e}",
                format!("'{name}'"),
                g["kind"].as_str().unwrap_or(""),
                f[0],
                f[1],
                mo
            );
        }
    }
    println!(
        "balance     loads F = ({:.4e}, {:.4e}), M = {:.4e}; loads + reactions F = ({:.2e}, {:.2e}), M = {:.2e}",
        lf[0],
        lf[1],
        lm,
        lf[0] + rf[0],
        lf[1] + rf[1],
        lm + rm
    );
    if let Some(ifs) = summary["contact"]["interfaces"].as_object() {
        for (name, i) in ifs {
            let (f, mo) = res2(i);
            println!(
                "interface   {:<14} on '{}': F = ({:.4e}, {:.4e}), M = {:.4e}; {} of {} rows active, max pressure {:.4e}",
                format!("'{name}'"),
                i["on_body"].as_str().unwrap_or(""),
                f[0],
                f[1],
                mo,
                i["active"],
                i["rows"],
                i["max_pressure"].as_f64().unwrap_or(f64::NAN)
            );
        }
    }
    for (name, x, node, u) in pipeline::probes(prep, &step.displacement) {
        println!(
            "probe {name:<5} ({:.6}, {:.6}) node {node}: u = ({:.6e}, {:.6e})",
            x[0], x[1], u[0], u[1]
        );
    }
    let phases: Vec<String> = res
        .timings
        .iter()
        .map(|(k, v)| format!("{k} {v:.3}"))
        .collect();
    println!(
        "time [s]    read {:.3}  assemble {:.3}  solve {:.3} ({})  write {:.3}  total {:.3}",
        t.read,
        t.assemble,
        t.solve,
        phases.join(", "),
        t.write,
        t.total
    );
    println!("outputs     {}", out.vtu.display());
    println!("            {}", out.contact_vtu.display());
    println!("            {}", out.h5.display());
    println!("            {}", out.json.display());
}
