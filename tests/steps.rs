//! Load steps: one VTU pair per step, a PVD time series, one HDF5 group per
//! step, warm starts; a run stopped after step 2 and restarted from its
//! checkpoint ends where an uninterrupted run ends.

mod common;

use common::{meshes, run};

fn example() -> String {
    common::example("three_bodies_steps")
}

#[test]
fn steps_write_a_time_series_and_restart_reproduces_the_uninterrupted_run() {
    let full = tempfile::tempdir().unwrap();
    let (code, log) = run(&["solve", &example(), "--out", full.path().to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    for k in 1..=4 {
        assert!(
            full.path()
                .join(format!("three_bodies_steps_{k:04}.vtu"))
                .exists(),
            "step {k} VTU"
        );
        assert!(full
            .path()
            .join(format!("three_bodies_steps_{k:04}_contact.vtu"))
            .exists());
    }
    let pvd = signorini::io::vtu::read_pvd(&full.path().join("three_bodies_steps.pvd")).unwrap();
    assert_eq!(pvd.len(), 8, "two datasets per step: {pvd:?}");
    let ck =
        signorini::io::hdf5::read_checkpoint(&full.path().join("three_bodies_steps.h5")).unwrap();
    assert_eq!(ck.steps.len(), 4);
    let times: Vec<f64> = ck.steps.iter().map(|s| s.time).collect();
    assert_eq!(times, vec![1.0, 2.0, 3.0, 4.0]);
    // The prescribed side displacement u_x = 0.2 m × factor of each step
    // (0.25, 0.5, 0.75, 1), the first step included.
    let left: Vec<usize> = ck
        .mesh
        .points
        .iter()
        .enumerate()
        .filter(|(_, p)| p[0] == 0.0)
        .map(|(i, _)| i)
        .collect();
    assert!(!left.is_empty());
    for (k, st) in ck.steps.iter().enumerate() {
        let want = 0.2 * 0.25 * (k + 1) as f64;
        for &p in &left {
            assert!(
                (st.displacement[p][0] - want).abs() < 1e-12,
                "step {}: u_x = {} want {want}",
                k + 1,
                st.displacement[p][0]
            );
        }
    }

    // Stopped after step 2, then restarted from the checkpoint.
    let part = tempfile::tempdir().unwrap();
    let (code, log) = run(&[
        "solve",
        &example(),
        "--out",
        part.path().to_str().unwrap(),
        "--max-steps",
        "2",
    ]);
    assert_eq!(code, 0, "{log}");
    let h5 = part.path().join("three_bodies_steps.h5");
    assert_eq!(
        signorini::io::hdf5::read_checkpoint(&h5)
            .unwrap()
            .steps
            .len(),
        2
    );
    let (code, log) = run(&[
        "solve",
        &example(),
        "--out",
        part.path().to_str().unwrap(),
        "--restart",
        h5.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    assert!(log.contains("restart"), "{log}");
    let ck2 = signorini::io::hdf5::read_checkpoint(&h5).unwrap();
    assert_eq!(ck2.steps.len(), 4);
    let scale = ck.steps[3]
        .displacement
        .iter()
        .fold(0.0f64, |m, u| m.max(u[0].abs()).max(u[1].abs()));
    for k in 0..4 {
        for (a, b) in ck.steps[k]
            .displacement
            .iter()
            .zip(&ck2.steps[k].displacement)
        {
            assert!(
                (a[0] - b[0]).abs() <= 1e-8 * scale && (a[1] - b[1]).abs() <= 1e-8 * scale,
                "step {}: {a:?} vs {b:?}",
                k + 1
            );
        }
        assert_eq!(ck.steps[k].active, ck2.steps[k].active, "step {}", k + 1);
    }
    // Restarting a finished run has nothing to do.
    let (code, log) = run(&[
        "solve",
        &example(),
        "--out",
        part.path().to_str().unwrap(),
        "--restart",
        h5.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    assert!(log.contains("nothing to do"), "{log}");
}

#[test]
fn restart_from_a_foreign_checkpoint_is_bad_input() {
    let d = tempfile::tempdir().unwrap();
    let col = meshes().join("column.toml");
    let (code, log) = run(&[
        "solve",
        col.to_str().unwrap(),
        "--out",
        d.path().to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{log}");
    let h5 = d.path().join("column.h5");
    let (code, log) = run(&[
        "solve",
        &example(),
        "--out",
        d.path().join("x").to_str().unwrap(),
        "--restart",
        h5.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{log}");
    assert!(log.contains("does not match"), "{log}");
}

/// C is the same in every load step: the later steps reuse the numeric
/// Cholesky factor of the first (one `Workspace` for all steps), and the answer is the
/// one a fresh factorization gives.
#[test]
fn load_steps_reuse_the_factorization() {
    use signorini::linalg::cholesky::Workspace;
    use signorini::qp::{registry, SolveOptions};
    use signorini::run;
    let prep = run::prepare(std::path::Path::new(&example()), false).unwrap();
    let opts = SolveOptions::default();
    let ws = Workspace::new();
    let (n0, _) = ws.reuse_counts();
    let mut xs = vec![];
    for s in 0..prep.problem.file.nsteps() {
        let model = run::step_model(&prep, s).unwrap();
        let r = registry::solve_in("mprgp", &model.qp, &opts, &ws).unwrap();
        assert!(r.status.converged());
        xs.push((model, r.solution.x));
    }
    let (n1, _) = ws.reuse_counts();
    assert!(
        n1 - n0 >= xs.len() - 1,
        "{} reuses over {} steps",
        n1 - n0,
        xs.len()
    );
    // The last step again with a fresh workspace: the same solution.
    let (model, x) = xs.last().unwrap();
    let r = registry::solve("mprgp", &model.qp, &opts).unwrap();
    let dx =
        r.x.iter()
            .zip(x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
    let xm = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(dx <= 1e-8 * xm, "{dx}");
}

/// A load step's model reuses the prepared C, A and elimination and
/// computes only d, g and u0 again (`run::step_model_reusing`, the last
/// step's model given up for the next, as a run does): every step of the
/// shipped step models, solved by ssn with warm starts, gives the same x,
/// bit for bit, as a full assembly of that step (`fem::build_with`).
#[test]
fn reused_assembly_gives_the_answers_of_a_fresh_one_bit_for_bit() {
    use signorini::linalg::cholesky::Workspace;
    use signorini::qp::{registry, SolveOptions};
    use signorini::run;
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for name in ["three_bodies_steps", "geodynamic_steps"] {
        let path = common::example(name);
        let prep = run::prepare(std::path::Path::new(&path), false).unwrap();
        let nsteps = prep.problem.file.nsteps();
        assert!(nsteps > 1, "{name}");
        let (ws_reused, ws_fresh) = (Workspace::new(), Workspace::new());
        let mut u_prev: Option<Vec<[f64; 2]>> = None;
        // As a run makes them: each step's model from the last one's.
        let mut prev = None;
        for s in 0..nsteps {
            let reused = run::step_model_reusing(&prep, s, prev.take()).unwrap();
            let mut p = prep.problem.clone();
            p.file = prep.problem.file.at_step(s);
            let fresh = signorini::fem::build_with(&prep.mesh, &p, &prep.build).unwrap();
            let at = format!("{name} step {}", s + 1);
            assert_eq!(bits(&reused.qp.d), bits(&fresh.qp.d), "d, {at}");
            assert_eq!(bits(&reused.qp.g), bits(&fresh.qp.g), "g, {at}");
            let mut xs = vec![];
            for (model, ws) in [(&reused, &ws_reused), (&fresh, &ws_fresh)] {
                let opts = SolveOptions {
                    x0: u_prev.as_ref().map(|u| run::reduce(model, u)),
                    ..SolveOptions::default()
                };
                let r = registry::solve_in("ssn", &model.qp, &opts, ws).unwrap();
                assert!(r.status.converged(), "{at}");
                xs.push(r.solution.x);
            }
            assert_eq!(bits(&xs[0]), bits(&xs[1]), "x, {at}");
            u_prev = Some(reused.displacements(&xs[0]));
            prev = Some(reused);
        }
    }
}

/// ssn keeps what it derives from C and A alone across load steps (the
/// bordered factor, A K⁻¹Aᵀ, the factors of S_J: `qp::ssn::Kept`): every
/// step solved with the run's one workspace gives the answer, the working
/// set and the counts that a fresh workspace gives for that step from the
/// same warm start (the last step's active rows, as a run passes them),
/// bit for bit, so a step's answer does not depend on what was kept. The
/// warm start itself changes the answer only at rounding level (the same
/// working set, reached in fewer dual-space steps).
#[test]
fn ssn_kept_across_steps_gives_each_steps_fresh_answer_bit_for_bit() {
    use signorini::linalg::cholesky::Workspace;
    use signorini::qp::{registry, SolveOptions};
    use signorini::run;
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for name in ["three_bodies_steps", "geodynamic_steps"] {
        let path = common::example(name);
        let prep = run::prepare(std::path::Path::new(&path), false).unwrap();
        let ws = Workspace::new();
        let mut prev = None;
        let mut active_prev: Option<Vec<u8>> = None;
        let mut warm_used = 0;
        for s in 0..prep.problem.file.nsteps() {
            let model = run::step_model_reusing(&prep, s, prev.take()).unwrap();
            let opts = SolveOptions {
                active0: active_prev
                    .as_deref()
                    .and_then(|a| run::reduce_active(&model, a)),
                ..SolveOptions::default()
            };
            warm_used += opts.active0.is_some() as usize;
            let kept = registry::solve_in("ssn", &model.qp, &opts, &ws).unwrap();
            let fresh = registry::solve_in("ssn", &model.qp, &opts, &Workspace::new()).unwrap();
            let cold = registry::solve_in(
                "ssn",
                &model.qp,
                &SolveOptions::default(),
                &Workspace::new(),
            )
            .unwrap();
            let at = format!("{name} step {}", s + 1);
            assert!(kept.status.converged(), "{at}");
            assert_eq!(bits(&kept.solution.x), bits(&fresh.solution.x), "x, {at}");
            assert_eq!(
                bits(&kept.solution.lambda),
                bits(&fresh.solution.lambda),
                "λ, {at}"
            );
            assert_eq!(kept.solution.active, fresh.solution.active, "{at}");
            assert_eq!(kept.solution.iterations, fresh.solution.iterations, "{at}");
            assert_eq!(
                kept.solution.inner_iterations, fresh.solution.inner_iterations,
                "{at}"
            );
            // Warm or cold: the same working set, the same answer to the certificate.
            assert_eq!(kept.solution.active, cold.solution.active, "{at}");
            let xmax = cold.solution.x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let dx = kept
                .solution
                .x
                .iter()
                .zip(&cold.solution.x)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                dx <= 1e-9 * xmax,
                "{at}: warm vs cold x differ by {dx:e} (max {xmax:e})"
            );
            // The run's flags per contact row, as post-processing makes them.
            let mut flags = vec![0u8; model.topo.contact.len()];
            for (qi, &r) in model.qp_rows.iter().enumerate() {
                flags[r] = kept.solution.active[qi] as u8;
            }
            active_prev = Some(flags);
            prev = Some(model);
        }
        assert!(warm_used > 0, "{name}: no step was warm-started");
    }
}

/// A step's explicit displacement for a component its `[[dirichlet]]`
/// group does not prescribe is dropped: the run warns, naming the step,
/// the group and the component (issue 43); a zero there (the step must give
/// two values, as every step of geodynamic_steps does) says nothing.
#[test]
fn a_step_value_for_a_free_component_is_named_in_a_warning() {
    let d = tempfile::tempdir().unwrap();
    let toml = common::model_variant(
        &meshes(),
        "geodynamic_steps.toml",
        &[("left_plate = [500.0, 0.0]", "left_plate = [500.0, 7.0]")],
        &d.path().join("free_uy.toml"),
    );
    for (toml, want) in [(toml, 1), (meshes().join("geodynamic_steps.toml"), 0)] {
        let out = d.path().join(format!("out{want}"));
        let (code, log) = run(&[
            "solve",
            toml.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--max-steps",
            "1",
        ]);
        assert_eq!(code, 0, "{log}");
        let warnings: Vec<&str> = log
            .lines()
            .filter(|l| l.contains("does not prescribe"))
            .collect();
        assert_eq!(warnings.len(), want, "{log}");
        if let Some(w) = warnings.first() {
            assert!(
                w.contains("free_uy.toml")
                    && w.contains("[[steps]] #3")
                    && w.contains("dirichlet.left_plate")
                    && w.contains("uy = 7"),
                "{w}"
            );
        }
    }
}
