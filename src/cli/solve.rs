//! `signorini solve`: one problem, one method, all outputs and the report.

use super::{SolveArgs, SolverFlags};
use crate::pipeline::{self, Prepared, SolverChoice};
use crate::post;
use crate::qp::QpResult;
use serde_json::json;
use std::path::PathBuf;
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

pub fn run(a: &SolveArgs, quiet: bool) -> i32 {
    let t0 = Instant::now();
    let prep = match pipeline::prepare(&a.problem, a.no_contact) {
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
        eprintln!(
            "error: {}: cannot create output directory: {e}",
            dir.display()
        );
        return EXIT_BAD_INPUT;
    }
    let name = prep.problem.name.clone();
    let file = &prep.problem.file;
    let multi = !file.steps.is_empty();
    let nsteps = file.nsteps();
    let last = a.max_steps.unwrap_or(nsteps).min(nsteps);
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let h5 = pipeline::output_paths(&dir, &name, None).h5;
    let compress = a.compress || file.output.compress;

    // Restart: the steps already in the checkpoint are kept; warm start from the last.
    let mut first = 0usize;
    let mut u_prev: Option<Vec<[f64; 2]>> = None;
    if let Some(rp) = &a.restart {
        let ck = match crate::io::hdf5::read_checkpoint(rp) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("error: --restart: {e}");
                return EXIT_BAD_INPUT;
            }
        };
        if ck.mesh.points.len() != om.points.len() || ck.mesh.triangles.len() != om.triangles.len()
        {
            eprintln!(
                "error: {}: checkpoint mesh ({} points, {} triangles) does not match {} ({} points, {} triangles)",
                rp.display(),
                ck.mesh.points.len(),
                ck.mesh.triangles.len(),
                a.problem.display(),
                om.points.len(),
                om.triangles.len()
            );
            return EXIT_BAD_INPUT;
        }
        first = ck.steps.len();
        u_prev = ck.steps.last().map(|s| s.displacement.clone());
        if rp.canonicalize().ok() != h5.canonicalize().ok() {
            if let Err(e) = crate::io::atomic::write_atomic(&h5, |tmp| {
                std::fs::copy(rp, tmp)
                    .map(|_| ())
                    .map_err(|cause| crate::io::IoError::Io {
                        path: h5.clone(),
                        action: "copy the checkpoint",
                        cause,
                    })
            }) {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        }
        if !quiet {
            println!(
                "restart     from step {first} of {} ({})",
                nsteps,
                rp.display()
            );
        }
    }
    // A new checkpoint is created only once the first step has solved, so bad
    // input (e.g. an unbounded problem) leaves no output file behind.
    let mut need_checkpoint = a.restart.is_none();

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
        let mut problem_s = prep.problem.clone();
        problem_s.file = file.at_step(s);
        let mut step = post::step_output(model_ref, &problem_s, &res, file.step_time(s));
        step.info.method = method.clone();
        step.info.preconditioner = preconditioner_label(&method, &opts);
        step.info.time_assemble = t_assemble;
        step.info.time_solve = t_solve;
        step.info.time_total = ts.elapsed().as_secs_f64();
        if need_checkpoint {
            if let Err(e) = pipeline::create_checkpoint(&prep, &out, &om) {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
            need_checkpoint = false;
        }
        if let Err(e) = pipeline::write_step(&out, &om, &step, s + 1, compress) {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
        if multi {
            let entries: Vec<(f64, String)> = (0..=s)
                .flat_map(|k| {
                    let o = pipeline::output_paths(&dir, &name, Some(k + 1));
                    let f = |p: &std::path::Path| {
                        p.file_name()
                            .map(|n| n.to_string_lossy().into_owned())
                            .unwrap_or_default()
                    };
                    [
                        (file.step_time(k), f(&o.vtu)),
                        (file.step_time(k), f(&o.contact_vtu)),
                    ]
                })
                .collect();
            if let Err(e) = crate::io::vtu::write_pvd(&dir.join(format!("{name}.pvd")), &entries) {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
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
        } else if !res.kkt.within(a.solver.kkt_target) {
            eprintln!(
                "warning: step {}: KKT residual {:.2e} above the target {:.0e}",
                s + 1,
                res.kkt.max(),
                a.solver.kkt_target
            );
            if a.solver.strict {
                code = EXIT_NOT_CONVERGED;
            }
        }
        u_prev = Some(step.displacement.clone());
        let timings = Timings {
            read: prep.t_read,
            assemble: t_assemble,
            solve: t_solve,
            write: t_write,
            total: 0.0,
        };
        final_state = Some((model, res, step, out, timings));
    }
    let Some((model, res, step, out, mut timings)) = final_state else {
        if !quiet {
            println!("nothing to do: the checkpoint already holds all {nsteps} steps");
        }
        return 0;
    };
    timings.total = t0.elapsed().as_secs_f64();
    let model_ref = model.as_ref().unwrap_or(&prep.model);
    let certified = res.kkt.within(a.solver.kkt_target);
    let mut summary = summary_json(
        &prep,
        model_ref,
        &res,
        &method,
        &step.info.preconditioner,
        &step,
        &timings,
        certified,
        a.solver.kkt_target,
    );
    if multi {
        summary["steps"] = json!(step_rows);
    }
    let text = match serde_json::to_string_pretty(&summary) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: JSON summary: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    if let Err(e) = crate::io::atomic::write_atomic_bytes(&out.json, text.as_bytes()) {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
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
    eprintln!("error: {e}");
    EXIT_BAD_INPUT
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
    let fo = post::forces::compute(
        m,
        &prep.problem,
        &step.displacement,
        &step.multipliers,
        &step.contact_pressure,
    );
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
            "target": target,
            "certified": certified,
        },
        "contact": { "max_pressure": max_p, "total_force": total, "interfaces": interfaces },
        "loads": fo.loads,
        "reactions": reactions,
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
        "KKT         primal {:.2e}  dual {:.2e}  complementarity {:.2e}  stationarity {:.2e}  → {}",
        k.primal,
        k.dual,
        k.complementarity,
        k.stationarity,
        if k.within(target) {
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
