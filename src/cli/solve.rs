//! `signorini solve`: parse the flags, run the library's pipeline
//! ([`crate::run`]), print the report, return the exit code
//! (docs/problem-format.md §8).

use super::progress::progress;
use super::SolveArgs;
use crate::post;
use crate::qp::{MethodId, SolveOptions};
use crate::run::{
    self, CheckpointWriter, Concurrent, Loaded, Outcome, Prepared, Progress, Restart, Run,
    RunError, SolidPrepared, SummaryWriter, Transaction, VtuWriter,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::run::{EXIT_BAD_INPUT, EXIT_NOT_CONVERGED};

pub fn run(a: &SolveArgs, quiet: bool, build: &crate::fem::BuildOptions) -> i32 {
    let t0 = Instant::now();
    // SIGTERM/SIGINT roll the outputs back (docs/problem-format.md §6).
    run::catch_signals();
    if let Some(target) = a.solver.flags.kkt_target {
        if !(target > 0.0 && target.is_finite()) {
            return bad_input(&format!(
                "--kkt-target {target}: the KKT target must be a positive number"
            ));
        }
    }
    if a.max_steps == Some(0) {
        return bad_input(&"--max-steps 0: load steps count from 1");
    }
    let prep = match run::load(&a.problem, a.no_contact, build) {
        Ok(Loaded::Plane(p)) => *p,
        Ok(Loaded::Solid(s)) => return solid(a, quiet, t0, &s),
        Err(e) => return bad_input(&e),
    };
    if let Some(p) = &a.start_from {
        return bad_input(&format!(
            "--start-from {}: {} is a 2D model; the nested start reads 3D checkpoints only (docs/methods.md §7.2)",
            p.display(),
            a.problem.display()
        ));
    }
    let (method, mut opts) = match run::options(&prep.problem, &a.solver.section()) {
        Ok(x) => x,
        Err(e) => return bad_input(&e),
    };
    opts.progress = progress(quiet);
    match solve(a, quiet, t0, &prep, method, &opts) {
        Ok(code) => code,
        Err(e) => {
            bad_input(&e);
            e.exit_code()
        }
    }
}

/// A 3D model (tetrahedra, no contact yet): solved and written by
/// [`run::solve_solid`], its report printed; the exit code as in 2D.
fn solid(a: &SolveArgs, quiet: bool, t0: Instant, prep: &SolidPrepared) -> i32 {
    let restart = match &a.restart {
        Some(p) => match run::solid::SolidRestart::read(p, prep) {
            Ok(r) => Some(r),
            Err(e) => return bad_input(&e),
        },
        None => None,
    };
    let nested = match &a.start_from {
        Some(p) => match run::solid::NestedStart::read(p, prep) {
            Ok(n) => Some(n),
            Err(e) => return bad_input(&e),
        },
        None => None,
    };
    let (method, mut opts) = match run::options(&prep.problem, &a.solver.section()) {
        Ok(x) => x,
        Err(e) => return bad_input(&e),
    };
    opts.progress = progress(quiet);
    let file = &prep.problem.file;
    let dir = a
        .out
        .clone()
        .or(file.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    let compress = a.compress || file.output.compress;
    let run = run::solid::SolidRun {
        method,
        opts: &opts,
        strict: a.solver.strict,
        max_steps: a.max_steps,
        restart: restart.as_ref(),
        nested: nested.as_ref(),
        compress,
        started: t0,
    };
    let outcome = match run::solve_solid(prep, &run, &dir) {
        Ok(Some(o)) => o,
        Ok(None) => {
            // A restart whose checkpoint holds every step asked for.
            let nsteps = file.nsteps();
            let done = restart.as_ref().map_or(0, |r| r.steps_done);
            if !quiet {
                match a.max_steps {
                    Some(k) if k < nsteps => crate::outln!(
                        "nothing to do: the checkpoint already holds {done} steps (--max-steps {k})"
                    ),
                    _ => crate::outln!(
                        "nothing to do: the checkpoint already holds all {nsteps} steps"
                    ),
                }
            }
            return 0;
        }
        Err(e) => {
            bad_input(&e);
            return e.exit_code();
        }
    };
    if !quiet {
        print_solid_report(prep, &outcome, nested.as_ref());
    }
    if outcome.certified {
        0
    } else {
        EXIT_NOT_CONVERGED
    }
}

/// The report of a 3D run: as 2D's, with 3-vectors.
fn print_solid_report(
    prep: &SolidPrepared,
    o: &run::SolidOutcome,
    nested: Option<&run::solid::NestedStart>,
) {
    let s = &o.summary;
    crate::outln!(
        "signorini {} — {} ({})",
        env!("CARGO_PKG_VERSION"),
        prep.problem.name,
        prep.problem.path.display()
    );
    crate::outln!(
        "mesh        {} nodes, {} tetrahedra, {} bodies (3D, solid)",
        s.nodes,
        s.tetrahedra,
        s.bodies
    );
    crate::outln!(
        "problem     {} DOFs, {} contact constraints",
        s.dofs,
        s.constraints
    );
    crate::outln!(
        "method      {} (preconditioner {}, ordering {})",
        s.method,
        s.preconditioner,
        s.ordering
    );
    if let Some(n) = nested {
        crate::outln!(
            "start       {} interpolated onto this mesh ({} step(s), {:.3} s; nested start, docs/methods.md §7.2)",
            n.path.display(),
            n.len(),
            n.seconds
        );
    }
    crate::outln!(
        "status      {} after {} iterations ({} inner)",
        s.status,
        s.iterations,
        s.inner_iterations
    );
    for note in &s.notes {
        crate::outln!("note        {note}");
    }
    let k = &s.kkt;
    crate::outln!(
        "KKT         primal {:.2e}  dual {:.2e}  complementarity {:.2e}  stationarity {:.2e}  → {}",
        k.primal,
        k.dual,
        k.complementarity,
        k.stationarity,
        // The verdict's words as in 2D (print_certificate).
        if k.certified && k.stationarity > k.target {
            format!(
                "certified at the rounding floor (stationarity floor {:.1e}; target {:.0e}; docs/methods.md §8.4)",
                k.stationarity_floor, k.target
            )
        } else if k.certified {
            format!("certified (≤ {:.0e})", k.target)
        } else {
            format!("NOT certified (target {:.0e})", k.target)
        }
    );
    crate::outln!(
        "energy      {:.6e} (QP objective); strain energy {:.6e}, work of the loads {:.6e}",
        s.energy,
        s.strain_energy,
        s.load_work
    );
    let v3 = |v: [f64; 3]| format!("({:.4e}, {:.4e}, {:.4e})", v[0], v[1], v[2]);
    let (mut rf, mut rm) = ([0.0; 3], [0.0; 3]);
    for (name, g) in &s.reactions {
        let r = &g.resultant;
        for k in 0..3 {
            rf[k] += r.force[k];
            rm[k] += r.moment[k];
        }
        crate::outln!(
            "reaction    {:<14} ({}) F = {}, M = {}",
            format!("'{name}'"),
            g.kind,
            v3(r.force),
            v3(r.moment)
        );
    }
    if !s.contact.is_empty() {
        crate::outln!("contact     {} active of {} rows", s.active, s.constraints);
    }
    for (name, it) in &s.contact {
        crate::outln!(
            "interface   '{name}': F = {}, M = {}; {} of {} rows active, max pressure {:.4e}",
            v3(it.resultant.force),
            v3(it.resultant.moment),
            it.active,
            it.rows,
            it.max_pressure
        );
        if let (Some(stick), Some(slip)) = (it.stick, it.slip) {
            crate::outln!(
                "friction    '{name}': {stick} rows stick, {slip} slip; friction residual {:.2e}",
                k.friction
            );
        }
    }
    let (lf, lm) = (s.loads.force, s.loads.moment);
    crate::outln!(
        "balance     loads F = {}, M = {} (about ({}, {}, {})); loads + reactions F = ({:.2e}, {:.2e}, {:.2e}), M = ({:.2e}, {:.2e}, {:.2e})",
        v3(lf),
        v3(lm),
        s.moment_point[0],
        s.moment_point[1],
        s.moment_point[2],
        lf[0] + rf[0],
        lf[1] + rf[1],
        lf[2] + rf[2],
        lm[0] + rm[0],
        lm[1] + rm[1],
        lm[2] + rm[2]
    );
    for (name, p) in &s.probes {
        let u = p.u.map(|v| if v == 0.0 { 0.0 } else { v });
        crate::outln!(
            "probe {name:<5} ({:.6}, {:.6}, {:.6}) node {}: u = ({:.6e}, {:.6e}, {:.6e})",
            p.x,
            p.y,
            p.z,
            p.node,
            u[0],
            u[1],
            u[2]
        );
    }
    if !s.steps.is_empty() {
        print_steps(&s.steps);
    }
    let t = &s.timings;
    crate::outln!(
        "time [s]    read {:.3}  assemble {:.3}  solve {:.3}  write {:.3}  total {:.3}",
        t.read,
        t.assemble,
        t.solve,
        t.write,
        t.total
    );
    for (i, f) in o.files.iter().enumerate() {
        let head = if i == 0 { "outputs" } else { "" };
        crate::outln!("{head:<11} {}", f.display());
    }
}

/// The run with every output; the exit code (0, or 3 for a step not
/// converged or not certified).
fn solve(
    a: &SolveArgs,
    quiet: bool,
    t0: Instant,
    prep: &Prepared,
    method: MethodId,
    opts: &SolveOptions,
) -> Result<i32, RunError> {
    let file = &prep.problem.file;
    let dir = a
        .out
        .clone()
        .or(file.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    // A signal during the reading leaves the directory untouched.
    if let Some(sig) = run::interrupted() {
        return Err(RunError::Interrupted(sig));
    }
    // The output directory is checked (and locked) before any time is spent
    // solving; an error drops `tx`, which puts the previous files back.
    let mut tx = Transaction::open(&dir, &prep.problem.name)?;
    let nsteps = file.nsteps();
    let restart = match &a.restart {
        Some(rp) => {
            let r = Restart::read(rp, prep)?;
            if !quiet {
                crate::outln!(
                    "restart     from step {} of {nsteps} ({})",
                    r.steps_done,
                    rp.display()
                );
            }
            Some(r)
        }
        None => None,
    };
    let om = post::out_mesh(&prep.model, &prep.mesh);
    let (sdir, fdir) = (tx.stage_dir().to_path_buf(), tx.dir().to_path_buf());
    let compress = a.compress || file.output.compress;
    let vtu = VtuWriter::new(prep, &om, &sdir, &fdir, compress).restart(restart.as_ref());
    let checkpoint = CheckpointWriter::new(prep, &om, &sdir, &fdir, restart.as_ref());
    // The VTU pair and the checkpoint are written side by side.
    let mut files = Concurrent(vtu, checkpoint);
    let mut json = SummaryWriter::new(prep, &sdir);
    let mut progress = Progress {
        quiet,
        // `-qq` and `--log-level error` hide the warnings, these too.
        warnings: log::max_level() >= log::LevelFilter::Warn,
    };
    let outcome = Run::new(prep, method, opts)
        .strict(a.solver.strict)
        .max_steps(a.max_steps)
        .restart(restart)
        .started(t0)
        .solve(&mut [&mut files, &mut json, &mut progress], Some(&mut tx))?;
    tx.finish();
    if !quiet {
        if outcome.last.is_none() {
            let first = outcome.steps.start;
            if first >= nsteps {
                crate::outln!("nothing to do: the checkpoint already holds all {nsteps} steps");
            } else {
                let last = a.max_steps.unwrap_or(nsteps).min(nsteps);
                crate::outln!(
                    "nothing to do: the checkpoint already holds {first} steps (--max-steps {last})"
                );
            }
        } else {
            print_report(prep, &outcome, &dir);
        }
    }
    Ok(if outcome.certified {
        0
    } else {
        EXIT_NOT_CONVERGED
    })
}

/// Print the one error line of bad input; the exit code for it.
pub(crate) fn bad_input(e: &impl std::fmt::Display) -> i32 {
    crate::errln!("error: {}", one_line(&e.to_string()));
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

/// The report on stdout: the problem, the last step's result, its
/// certificate, forces, probes, timings and output files.
fn print_report(prep: &Prepared, outcome: &Outcome, dir: &Path) {
    let (Some(last), Some(s)) = (&outcome.last, &outcome.summary) else {
        return;
    };
    let m = last.model(prep);
    let res = &last.result;
    crate::outln!(
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
    crate::outln!(
        "mesh        {} nodes ({} with interface copies), {} triangles, {} bodies{}",
        s.mesh_nodes,
        s.nodes,
        s.triangles,
        s.bodies,
        if floating.is_empty() {
            String::new()
        } else {
            format!(
                "; semicoercive: {} ({} rigid modes)",
                floating.join(", "),
                s.rigid_modes
            )
        }
    );
    crate::outln!(
        "problem     {} DOFs, {} contact constraints",
        s.dofs,
        s.constraints
    );
    crate::outln!(
        "method      {} (preconditioner {}, ordering {})",
        s.method,
        s.preconditioner,
        s.ordering
    );
    crate::outln!(
        "status      {} after {} iterations ({} inner)",
        s.status,
        s.iterations,
        s.inner_iterations
    );
    for note in &s.notes {
        crate::outln!("note        {note}");
    }
    print_certificate(s, !s.failed_steps.contains(&outcome.steps.end));
    if let (false, Some(rows)) = (s.failed_steps.is_empty(), &s.steps) {
        let failed: Vec<String> = rows
            .iter()
            .filter(|r| s.failed_steps.contains(&r.step))
            .map(|r| {
                let why = if r.converged {
                    "not certified"
                } else {
                    "not converged"
                };
                format!("step {} of {} ({why})", r.step, outcome.nsteps)
            })
            .collect();
        crate::outln!(
            "failed      {}; outputs written and flagged",
            failed.join(", ")
        );
    }
    print_forces(s);
    for (name, x, node, u) in run::probes(prep, &last.output.displacement) {
        // -0 prints as 0.
        let u = u.map(|v| if v == 0.0 { 0.0 } else { v });
        crate::outln!(
            "probe {name:<5} ({:.6}, {:.6}) node {node}: u = ({:.6e}, {:.6e})",
            x[0],
            x[1],
            u[0],
            u[1]
        );
    }
    if let Some(k) = s.reference_step {
        crate::outln!(
            "reference   step {k}: displacement_change, stress_change and contact_pressure_change (this step minus step {k}) in the VTU and HDF5 outputs of step {k} and later"
        );
    }
    if let Some(rows) = &s.steps {
        print_steps(rows);
    }
    let phases: Vec<String> = res
        .timings
        .iter()
        .map(|(k, v)| format!("{k} {v:.3}"))
        .collect();
    let t = &s.timings;
    crate::outln!(
        "time [s]    read {:.3}  assemble {:.3}  solve {:.3}{}  write {:.3}  total {:.3}",
        t.read,
        t.assemble,
        t.solve,
        if phases.is_empty() {
            String::new()
        } else {
            format!(" ({})", phases.join(", "))
        },
        t.write,
        t.total
    );
    let multi = !prep.problem.file.steps.is_empty();
    let out = run::output_paths(dir, &prep.problem.name, multi.then_some(outcome.steps.end));
    crate::outln!("outputs     {}", out.vtu.display());
    crate::outln!("            {}", out.contact_vtu.display());
    crate::outln!("            {}", out.h5.display());
    crate::outln!("            {}", out.json.display());
}

/// The KKT line: every residual of the last step and its verdict,
/// `certified` (docs/methods.md §8.4).
fn print_certificate(s: &run::Summary, certified: bool) {
    let k = &s.kkt;
    crate::outln!(
        "KKT         primal {:.2e}  dual {:.2e}  complementarity {:.2e}  stationarity {:.2e}  contact balance {:.2e}{}  → {}",
        k.primal,
        k.dual,
        k.complementarity,
        k.stationarity,
        k.contact_balance,
        if k.rigid_balance != 0.0 {
            format!("  rigid balance {:.2e}", k.rigid_balance)
        } else {
            String::new()
        },
        if certified && (k.stationarity > k.target || k.contact_balance > k.target) {
            format!(
                "certified at the rounding floor (stationarity floor {:.1e}, balance floor {:.1e}; \
                 target {:.0e}; docs/methods.md §8.4)",
                k.stationarity_floor, k.balance_floor, k.target
            )
        } else if certified {
            format!("certified (≤ {:.0e})", k.target)
        } else {
            format!("NOT certified (target {:.0e})", k.target)
        }
    );
}

/// Energy, contact, friction, reactions, the global balance and the
/// interface resultants (docs/problem-format.md §7).
fn print_forces(s: &run::Summary) {
    crate::outln!(
        "energy      {:.6e} (QP objective); strain energy {:.6e}, work of the loads {:.6e}",
        s.energy,
        s.strain_energy,
        s.load_work
    );
    crate::outln!(
        "contact     {} active of {}, max pressure {:.4e} (peak nodal), mean pressure {:.4e}, total force {:.4e}",
        s.active,
        s.constraints,
        s.contact.max_pressure,
        s.contact.mean_pressure,
        s.contact.total_force
    );
    if let (Some(stick), Some(slip)) = (s.contact.stick, s.contact.slip) {
        crate::outln!(
            "friction    {stick} rows stick, {slip} slip; friction residual {:.2e}",
            s.kkt.friction
        );
    }
    // Global balance: loads + reactions = 0 in force; in moment the couple
    // the contact forces make across initial gaps joins them (friction).
    let (lf, lm) = (s.loads.force, s.loads.moment);
    let mut rf = [0.0, 0.0];
    let mut rm = 0.0;
    for (name, g) in &s.reactions {
        let (f, mo) = (g.resultant.force, g.resultant.moment);
        rf = [rf[0] + f[0], rf[1] + f[1]];
        rm += mo;
        crate::outln!(
            "reaction    {:<14} ({}) F = ({:.4e}, {:.4e}), M = {:.4e}",
            format!("'{name}'"),
            g.kind,
            f[0],
            f[1],
            mo
        );
    }
    crate::outln!(
        "balance     loads F = ({:.4e}, {:.4e}), M = {:.4e}; loads + reactions F = ({:.2e}, {:.2e}), M = {:.2e}",
        lf[0],
        lf[1],
        lm,
        lf[0] + rf[0],
        lf[1] + rf[1],
        lm + rm
    );
    // Round-off couples of frictionless rows are not worth a line.
    let mscale = s
        .reactions
        .values()
        .fold(lm.abs(), |a, g| a.max(g.resultant.moment.abs()));
    if s.contact.couple.abs() > 1e-12 * mscale {
        crate::outln!(
            "            contact couple M = {:.4e} (contact forces across initial gaps); loads + reactions + couple M = {:.2e}",
            s.contact.couple,
            lm + rm + s.contact.couple
        );
    }
    if let Some(unit) = s.force_unit {
        // A ring's radial forces and moments are no resultant: only the
        // axial sum balances (docs/problem-format.md §11).
        crate::outln!(
            "            axisymmetric: forces in {unit}; only the axial (y) sum balances"
        );
    }
    for (name, i) in &s.contact.interfaces {
        let (f, mo) = (i.resultant.force, i.resultant.moment);
        crate::outln!(
            "interface   {:<14} on '{}': F = ({:.4e}, {:.4e}), M = {:.4e}; {} of {} rows active, max pressure {:.4e}, mean {:.4e}{}",
            format!("'{name}'"),
            i.on_body,
            f[0],
            f[1],
            mo,
            i.active,
            i.rows,
            i.max_pressure,
            i.mean_pressure,
            match &i.extent {
                Some(e) => format!(
                    "; contact from ({:.4e}, {:.4e}) to ({:.4e}, {:.4e}), arc {:.4e}, {} zone{}",
                    e.start[0],
                    e.start[1],
                    e.end[0],
                    e.end[1],
                    e.length,
                    e.zones,
                    if e.zones == 1 { "" } else { "s" }
                ),
                None => String::new(),
            }
        );
    }
}

/// The per-step table (the report's §3.4 table; `steps` in the JSON).
fn print_steps(rows: &[run::StepRow]) {
    let cells = rows.first().map_or("cells", |r| r.cells.name());
    crate::outln!(
        "steps       {:>5} {:>10} {:>8} {:>9} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>9} {:>9}",
        "step",
        "t",
        "nodes",
        cells,
        "DOFs",
        "rows",
        "active",
        "opened",
        "closed",
        "iter",
        "solve [s]",
        "step [s]"
    );
    let opt = |v: Option<usize>| v.map_or_else(|| "-".to_string(), |v| v.to_string());
    for r in rows {
        crate::outln!(
            "            {:>5} {:>10} {:>8} {:>9} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>9.3} {:>9.3}{}",
            r.step,
            format!("{}", r.t),
            r.nodes,
            r.cells.count(),
            r.dofs,
            r.constraints,
            r.active,
            opt(r.opened),
            opt(r.closed),
            r.iterations,
            r.time_solve,
            r.time_step,
            if !r.converged {
                "  NOT CONVERGED"
            } else if !r.certified {
                "  NOT CERTIFIED"
            } else {
                ""
            }
        );
    }
}
