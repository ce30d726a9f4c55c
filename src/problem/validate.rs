//! Checks of the problem file that need no mesh, and the one conversion of
//! the raw entries ([`super::raw`]) into typed ones: a file either becomes a
//! [`ProblemFile`] whose entries cannot be contradictory, or gives one
//! message naming the table, entry and key (the caller adds the file).
//! Names are checked against the mesh in `fem::topology`.

use super::raw::{RawContact, RawDirichlet, RawFile, RawTraction, RawTurn};
use super::{
    num, shorten, Contact, ContactPair, Dirichlet, Discretization, FrictionLaw, NonMatchingPair,
    Prescribed, ProblemFile, Traction, TractionLoad, Turn, MAX_MAGNITUDE, MAX_NAME,
};
use crate::fem::ElementKind;

type Check<T = ()> = Result<T, String>;

/// The whole file, in the order the checks have always run (the first
/// error found is the one reported).
pub(super) fn validate(raw: RawFile) -> Check<ProblemFile> {
    check_names(&raw)?;
    check_contact_not_supported(&raw)?;
    check_magnitudes(&raw)?;
    check_model(&raw)?;
    check_materials(&raw)?;
    let dirichlet = collect(&raw.dirichlet, dirichlet)?;
    let traction = collect(&raw.traction, traction)?;
    for fo in &raw.force {
        if !fo.f.values().iter().all(|v| v.is_finite()) {
            return Err(format!(
                "[[force]] on = \"{}\": values must be finite",
                fo.on
            ));
        }
    }
    let contact = collect(&raw.contact, contact)?;
    check_pairs_once(&contact)?;
    check_one_friction_law(&contact)?;
    check_solver(&raw)?;
    check_steps(&raw)?;
    check_output(&raw)?;
    Ok(ProblemFile {
        mesh: raw.mesh,
        model: raw.model,
        materials: raw.materials,
        dirichlet,
        traction,
        slip: raw.slip,
        force: raw.force,
        contact,
        solver: raw.solver,
        output: raw.output,
        steps: raw.steps,
    })
}

/// Above this Poisson ratio [`warnings`] says that linear elements lock.
pub const NU_LOCKING: f64 = 0.45;

/// What a valid file leaves unused or asks of the elements beyond what they
/// do well, as messages naming the table and entry (logged as warnings by
/// the caller, which adds the file): a Poisson ratio above [`NU_LOCKING`];
/// a `[[steps]]`
/// value for a displacement component that its `[[dirichlet]]` group does
/// not prescribe is dropped (the component stays free); the step must give
/// two values, so only a non-zero one is reported.
pub(super) fn warnings(f: &ProblemFile) -> Vec<String> {
    let mut out = vec![];
    // Linear elements lock as ν → 0.5 (docs/guide.md, "Nearly
    // incompressible materials"): allowed, but said.
    let locks = ElementKind::of(&f.model).locks_near_incompressible();
    for (name, m) in f.materials.iter().filter(|_| locks) {
        if m.nu > NU_LOCKING {
            out.push(format!(
                "[materials.{name}] nu = {}: linear (P1) elements lock as nu approaches 0.5, so displacements come out too small and stresses oscillate from element to element (a 3D cantilever's tip deflection at nu = 0.49 is 64 % of its value at nu = 0.3 on a coarse mesh, 83 % on one twice as fine: docs/guide.md, \"Nearly incompressible materials\"); refine where it matters and read stresses as averages",
                num(m.nu)
            ));
        }
    }
    for (i, st) in f.steps.iter().enumerate() {
        for d in &f.dirichlet {
            let Some(u) = st.dirichlet.get(&d.on) else {
                continue;
            };
            let held = d.value.components();
            for (k, axis) in ["ux", "uy", "uz"].iter().enumerate().take(u.len()) {
                let uk = u.values()[k];
                if held[k].is_none() && uk != 0.0 {
                    out.push(format!(
                        "[[steps]] #{}: dirichlet.{} = {} sets {axis} = {}, but [[dirichlet]] on = \"{}\" does not prescribe {axis}: the value is ignored and {axis} stays free (add {axis} to that [[dirichlet]] to prescribe it)",
                        i + 1,
                        shorten(&d.on),
                        u.show(),
                        num(uk),
                        shorten(&d.on)
                    ));
                }
            }
        }
    }
    out
}

/// Converts entry #i of a `[[table]]` array by `f(i, entry)`.
fn collect<R, T>(raw: &[R], f: impl Fn(usize, &R) -> Check<T>) -> Check<Vec<T>> {
    raw.iter().enumerate().map(|(i, r)| f(i, r)).collect()
}

/// Names are echoed in messages, which must stay one line: no control
/// characters (a TOML escape such as "\n" could put one there), and no
/// longer than [`MAX_NAME`].
fn check_names(f: &RawFile) -> Check {
    let mut names: Vec<(&str, &str)> = vec![];
    names.extend(f.materials.keys().map(|n| ("[materials.NAME]", n.as_str())));
    names.extend(
        f.dirichlet
            .iter()
            .map(|d| ("[[dirichlet]] on", d.on.as_str())),
    );
    names.extend(
        f.traction
            .iter()
            .map(|t| ("[[traction]] on", t.on.as_str())),
    );
    names.extend(f.slip.iter().map(|s| ("[[slip]] on", s.on.as_str())));
    names.extend(f.force.iter().map(|x| ("[[force]] on", x.on.as_str())));
    for c in &f.contact {
        for (key, n) in c.names() {
            let what = match key {
                "on" => "[[contact]] on",
                "slave" => "[[contact]] slave",
                _ => "[[contact]] master",
            };
            names.push((what, n));
        }
    }
    for st in &f.steps {
        names.extend(
            st.dirichlet
                .keys()
                .map(|n| ("[[steps]] dirichlet", n.as_str())),
        );
    }
    names.extend(
        f.output
            .probes
            .keys()
            .map(|n| ("[output] probes", n.as_str())),
    );
    let mesh_file = f.mesh.file.to_string_lossy();
    names.push(("[mesh] file", &mesh_file));
    for (what, n) in names {
        if n.chars().any(char::is_control) {
            return Err(format!(
                "{what}: the name {:?} contains a control character",
                shorten(n)
            ));
        }
        if n.len() > MAX_NAME {
            return Err(format!(
                "{what}: the name \"{}\" is longer than {MAX_NAME} bytes",
                shorten(n)
            ));
        }
    }
    Ok(())
}

/// A contact curve (conforming, or the slave side) that is also fixed or
/// sliding: the contact rows of its points would be dropped without a
/// word. A fixed master is an obstacle and stays allowed.
fn check_contact_not_supported(f: &RawFile) -> Check {
    for (i, c) in f.contact.iter().enumerate() {
        for n in [&c.on, &c.slave].into_iter().flatten() {
            let fixed = f
                .dirichlet
                .iter()
                .map(|d| ("[[dirichlet]]", &d.on))
                .chain(f.slip.iter().map(|s| ("[[slip]]", &s.on)))
                .find(|(_, on)| *on == n);
            if let Some((what, _)) = fixed {
                return Err(format!(
                    "[[contact]] #{}: curve \"{}\" is also in {what}; a curve is either in contact or supported, not both",
                    i + 1,
                    shorten(n)
                ));
            }
        }
    }
    Ok(())
}

/// Whether a finite `v` lies beyond ±[`MAX_MAGNITUDE`].
fn beyond(v: f64) -> bool {
    v.is_finite() && v.abs() > MAX_MAGNITUDE
}

/// Loads, prescribed displacements and E: their products (stiffness ×
/// displacement, energy) must stay far inside the range of double precision.
fn check_magnitudes(f: &RawFile) -> Check {
    let mut loads: Vec<(String, f64)> = vec![];
    if let Some(g) = f.model.gravity {
        loads.extend(
            g.values()
                .iter()
                .map(|v| ("[model] gravity".to_string(), *v)),
        );
    }
    for d in &f.dirichlet {
        let what = format!("[[dirichlet]] on = \"{}\": u", shorten(&d.on));
        loads.extend(d.values().map(|v| (what.clone(), v)));
    }
    for t in &f.traction {
        let what = format!("[[traction]] on = \"{}\": p", shorten(&t.on));
        loads.extend(t.values().map(|v| (what.clone(), v)));
    }
    for x in &f.force {
        let what = format!("[[force]] on = \"{}\": f", shorten(&x.on));
        loads.extend(x.f.values().iter().map(|v| (what.clone(), *v)));
    }
    if let Some((what, v)) = loads.into_iter().find(|(_, v)| beyond(*v)) {
        return Err(format!(
            "{what} = {v:e} is beyond ±{MAX_MAGNITUDE:e}: products with it would overflow; change the units"
        ));
    }
    for (name, m) in &f.materials {
        if m.e.is_finite() && m.e > 0.0 && (beyond(m.e) || m.e < 1.0 / MAX_MAGNITUDE) {
            return Err(format!(
                "[materials.{}] E = {:e} lies outside [{:e}, {MAX_MAGNITUDE:e}]: stiffness products would underflow or overflow; change the units",
                shorten(name),
                m.e,
                1.0 / MAX_MAGNITUDE
            ));
        }
    }
    Ok(())
}

fn check_model(f: &RawFile) -> Check {
    let t = f.model.thickness;
    if !(t > 0.0 && t.is_finite()) {
        return Err(format!("[model] thickness = {} must be positive", num(t)));
    }
    if let Some(g) = f.model.gravity {
        if !g.values().iter().all(|v| v.is_finite()) {
            return Err("[model] gravity must be finite".into());
        }
        // A 3-vector is held against the mesh (Problem::check_dimension).
        let misfit = (g.len() == 2)
            .then(|| ElementKind::of(&f.model).gravity_misfit(g.xy()))
            .flatten();
        if let Some(why) = misfit {
            return Err(format!(
                "[model] gravity = [{}, {}]: {why}",
                num(g.xy()[0]),
                num(g.xy()[1])
            ));
        }
    }
    if let Some(w) = f.model.omega {
        if !w.is_finite() {
            return Err(format!("[model] omega = {} must be finite", num(w)));
        }
        if beyond(w) {
            return Err(format!(
                "[model] omega = {} is beyond ±{MAX_MAGNITUDE:e}: the centrifugal load ρω²r would overflow; change the units",
                num(w)
            ));
        }
        if let Some(why) = ElementKind::of(&f.model).spin_misfit() {
            return Err(format!("[model] omega (a spin about the axis) {why}"));
        }
    }
    Ok(())
}

fn check_materials(f: &RawFile) -> Check {
    if f.materials.is_empty() {
        return Err("no [materials.NAME] table: every physical surface needs a material".into());
    }
    for (name, m) in &f.materials {
        if !(m.e > 0.0 && m.e.is_finite()) {
            return Err(format!(
                "[materials.{name}] E = {} must be positive",
                num(m.e)
            ));
        }
        if !(m.nu > -1.0 && m.nu < 0.5) {
            return Err(format!(
                "[materials.{name}] nu = {} must lie in (-1, 0.5)",
                num(m.nu)
            ));
        }
        if !(m.rho >= 0.0 && m.rho.is_finite()) {
            return Err(format!(
                "[materials.{name}] rho = {} must be non-negative",
                num(m.rho)
            ));
        }
    }
    Ok(())
}

/// `[[dirichlet]]` #i: `u = [ux, uy]` (or `[ux, uy, uz]`), any of `ux`,
/// `uy`, `uz`, finite, or a `turn` alone ([`turn`]).
fn dirichlet(i: usize, d: &RawDirichlet) -> Check<Dirichlet> {
    if let Some(t) = &d.turn {
        let given: Vec<&str> = [
            ("u", d.u.is_some()),
            ("ux", d.ux.is_some()),
            ("uy", d.uy.is_some()),
            ("uz", d.uz.is_some()),
        ]
        .iter()
        .filter(|k| k.1)
        .map(|k| k.0)
        .collect();
        if !given.is_empty() {
            return Err(format!(
                "[[dirichlet]] #{} (on = \"{}\"): turn excludes {}: a turn prescribes u·e_θ only; put the other components in an entry of their own",
                i + 1,
                shorten(&d.on),
                given.join(", ")
            ));
        }
        return Ok(Dirichlet {
            on: d.on.clone(),
            value: Prescribed::Turn(turn(i, &d.on, t)?),
        });
    }
    let value = match (d.u, d.ux, d.uy, d.uz) {
        (Some(u), None, None, None) => Prescribed::All(u),
        (None, ux, uy, uz) if ux.is_some() || uy.is_some() || uz.is_some() => {
            Prescribed::Components { ux, uy, uz }
        }
        _ => {
            return Err(format!(
                "[[dirichlet]] #{} (on = \"{}\"): give either u = [ux, uy] or ux and/or uy (or a turn = {{ angle, axis, origin }})",
                i + 1,
                d.on
            ))
        }
    };
    if !d.values().all(f64::is_finite) {
        return Err(format!(
            "[[dirichlet]] on = \"{}\": values must be finite",
            d.on
        ));
    }
    Ok(Dirichlet {
        on: d.on.clone(),
        value,
    })
}

/// `turn` of `[[dirichlet]]` #i on `on`: a finite angle within
/// ±[`MAX_MAGNITUDE`], a finite origin, a finite non-zero axis (made unit).
/// Which keys the mesh's dimension takes is checked with the mesh
/// (`Problem::check_dimension`).
fn turn(i: usize, on: &str, t: &RawTurn) -> Check<Turn> {
    let at = format!("[[dirichlet]] #{} (on = \"{}\")", i + 1, shorten(on));
    if !t.angle.is_finite() || beyond(t.angle) {
        return Err(format!(
            "{at}: turn.angle = {} must be finite and within ±{MAX_MAGNITUDE:e} (radians)",
            num(t.angle)
        ));
    }
    if let Some(o) = t.origin {
        if let Some(v) = o.values().iter().find(|v| !v.is_finite() || beyond(**v)) {
            return Err(format!(
                "{at}: turn.origin = {}: {} must be finite and within ±{MAX_MAGNITUDE:e}",
                o.show(),
                num(*v)
            ));
        }
    }
    let axis = match t.axis {
        None => None,
        Some(a) => {
            let big = a.values().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if !(a.values().iter().all(|v| v.is_finite()) && big > 0.0) {
                return Err(format!(
                    "{at}: turn.axis = {}: the axis must be a finite, non-zero vector",
                    a.show()
                ));
            }
            let s = a.scaled(1.0 / big);
            let len = s.values().iter().map(|v| v * v).sum::<f64>().sqrt();
            Some(s.scaled(1.0 / len))
        }
    };
    Ok(Turn {
        angle: t.angle,
        axis,
        origin: t.origin,
    })
}

/// `[[traction]]` #i: exactly one of `p = [px, py]` and `pn`, finite.
fn traction(i: usize, t: &RawTraction) -> Check<Traction> {
    let load = match (t.p, t.pn) {
        (Some(p), None) => TractionLoad::Vector(p),
        (None, Some(pn)) => TractionLoad::Normal(pn),
        _ => {
            return Err(format!(
                "[[traction]] #{} (on = \"{}\"): give exactly one of p = [px, py] or pn",
                i + 1,
                t.on
            ))
        }
    };
    if !t.values().all(f64::is_finite) {
        return Err(format!(
            "[[traction]] on = \"{}\": values must be finite",
            t.on
        ));
    }
    Ok(Traction {
        on: t.on.clone(),
        load,
    })
}

/// `[[contact]]` #i: its form (`on`, or `slave` and `master`), the keys
/// that apply to that form only, and the friction law.
fn contact(i: usize, c: &RawContact) -> Check<Contact> {
    let n = i + 1;
    let pair = match (&c.on, &c.slave, &c.master) {
        (Some(on), None, None) => ContactPair::Conforming {
            on: on.clone(),
            normals: c.normals.unwrap_or_default(),
        },
        (None, Some(slave), Some(master)) => ContactPair::NonMatching(NonMatchingPair {
            slave: slave.clone(),
            master: master.clone(),
            max_gap: c.max_gap,
            discretization: None,
            interference: c.interference.unwrap_or(false),
        }),
        _ => {
            return Err(format!(
                "[[contact]] #{n}: give either on = \"curve\" (conforming) or both slave and master (non-matching)"
            ))
        }
    };
    let mut typed = Contact {
        pair,
        friction: FrictionLaw::Frictionless,
    };
    let at = format!("[[contact]] #{n} ({})", typed.keys());
    if let Some(g) = c.max_gap {
        if g.is_nan() || g < 0.0 {
            return Err(format!("{at}: max_gap = {g} must be >= 0"));
        }
    }
    typed.friction = friction_law(c, &at)?;
    match &mut typed.pair {
        ContactPair::Conforming { .. } => {
            // Keys of the other form would be dropped without a word.
            let other = [
                ("discretization", c.discretization.is_some()),
                ("max_gap", c.max_gap.is_some()),
                ("interference", c.interference.is_some()),
            ];
            if let Some((key, _)) = other.iter().find(|k| k.1) {
                return Err(format!(
                    "{at}: {key} applies to non-matching pairs (slave, master) only; a conforming pair has node-to-node rows"
                ));
            }
        }
        ContactPair::NonMatching(p) => {
            if c.normals.is_some() {
                return Err(format!(
                    "{at}: normals applies to conforming pairs (on = \"curve\") only; a non-matching pair takes the master's normal (nts) or the slave's (mortar)"
                ));
            }
            p.discretization = match c.discretization.as_deref() {
                None => None,
                Some("nts") => Some(Discretization::Nts),
                Some("mortar") => Some(Discretization::Mortar),
                Some(d) => {
                    return Err(format!(
                        "{at}: discretization = {:?} is unknown; use \"nts\" or \"mortar\"",
                        shorten(d)
                    ))
                }
            };
        }
    }
    Ok(typed)
}

/// `friction = μ` or `tresca = s` (not both), finite, ≥ 0 and at most
/// [`MAX_MAGNITUDE`]: the row bound (μ λ_n, or s × tributary length ×
/// thickness, docs/methods.md §9) must stay finite; `friction = 0` is no
/// friction.
fn friction_law(c: &RawContact, at: &str) -> Check<FrictionLaw> {
    if c.friction.is_some() && c.tresca.is_some() {
        return Err(format!(
            "{at}: give either friction = μ (Coulomb) or tresca = s (Tresca), not both"
        ));
    }
    for (key, v) in [("friction", c.friction), ("tresca", c.tresca)] {
        let Some(v) = v else { continue };
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "{at}: {key} = {} must be a finite number >= 0",
                num(v)
            ));
        }
        if v > MAX_MAGNITUDE {
            return Err(format!(
                "{at}: {key} = {v:e} is beyond {MAX_MAGNITUDE:e}: the friction bound of a row would overflow; change the units"
            ));
        }
    }
    Ok(match (c.friction, c.tresca) {
        (_, Some(s)) => FrictionLaw::Tresca(s),
        (Some(mu), None) if mu > 0.0 => FrictionLaw::Coulomb(mu),
        _ => FrictionLaw::Frictionless,
    })
}

/// One entry per pair. Two entries naming the same groups (the same `on`
/// curve, or the same two curves as slave and master in either order)
/// would give every node its rows twice, or one entry's keys (friction,
/// discretization) would silently lose to the other's. Curves of other
/// names that share segments are found with the mesh (`fem::topology`,
/// `fem::pairs`).
fn check_pairs_once(contact: &[Contact]) -> Check {
    for (j, b) in contact.iter().enumerate() {
        let mut gb = b.groups();
        gb.sort_unstable();
        let same = contact[..j].iter().position(|a| {
            let mut ga = a.groups();
            ga.sort_unstable();
            ga == gb
        });
        if let Some(i) = same {
            return Err(format!(
                "[[contact]] #{} ({}) and #{} ({}) pair the same curves; give each pair once, with all its keys in one entry",
                i + 1,
                contact[i].keys(),
                j + 1,
                b.keys()
            ));
        }
    }
    Ok(())
}

/// Tresca and Coulomb pairs in one problem: the QP holds one kind of slip
/// bound (docs/methods.md §9), so the mix is refused naming one of each.
fn check_one_friction_law(contact: &[Contact]) -> Check {
    let first = |tresca: bool| {
        contact.iter().position(|c| match c.friction {
            FrictionLaw::Tresca(_) => tresca,
            FrictionLaw::Coulomb(_) => !tresca,
            FrictionLaw::Frictionless => false,
        })
    };
    if let (Some(t), Some(c)) = (first(true), first(false)) {
        return Err(format!(
            "[[contact]] #{} ({}) has tresca = s and #{} ({}) friction = μ: Tresca and Coulomb pairs in one problem are not supported; use one law for every pair",
            t + 1,
            contact[t].keys(),
            c + 1,
            contact[c].keys()
        ));
    }
    Ok(())
}

fn check_solver(f: &RawFile) -> Check {
    let s = &f.solver;
    if let Some(t) = s.tol {
        if !(t > 0.0 && t < 1.0) {
            return Err(format!("[solver] tol = {} must lie in (0, 1)", num(t)));
        }
    }
    if s.max_iter == Some(0) {
        return Err("[solver] max_iter must be positive".into());
    }
    Ok(())
}

/// `[[steps]]`: finite values, increasing t, and explicit displacements only
/// for groups that have a `[[dirichlet]]`.
fn check_steps(f: &RawFile) -> Check {
    let mut last_t = f64::NEG_INFINITY;
    for (i, st) in f.steps.iter().enumerate() {
        let n = i + 1;
        let values = [st.t, st.factor, st.load, st.displacement];
        if !values.into_iter().flatten().all(f64::is_finite) {
            return Err(format!("[[steps]] #{n}: values must be finite"));
        }
        let factors = [
            ("factor", st.factor),
            ("load", st.load),
            ("displacement", st.displacement),
        ];
        for (key, v) in factors {
            if let Some(v) = v.filter(|v| beyond(*v)) {
                return Err(format!(
                    "[[steps]] #{n}: {key} = {} is beyond ±{MAX_MAGNITUDE:e}: the loads it scales would overflow; change the units",
                    num(v)
                ));
            }
        }
        let t = st.t.unwrap_or(n as f64);
        if t <= last_t {
            return Err(format!(
                "[[steps]] #{n}: t = {} must increase from step to step",
                num(t)
            ));
        }
        last_t = t;
        for (name, u) in &st.dirichlet {
            if !f.dirichlet.iter().any(|d| &d.on == name) {
                return Err(format!(
                    "[[steps]] #{n}: dirichlet.{name}: no [[dirichlet]] with on = \"{name}\""
                ));
            }
            if f.dirichlet
                .iter()
                .any(|d| &d.on == name && d.turn.is_some())
            {
                return Err(format!(
                    "[[steps]] #{n}: dirichlet.{}: [[dirichlet]] on = \"{}\" is a turn, which takes no explicit step values; scale its angle with the step's displacement (or factor)",
                    shorten(name),
                    shorten(name)
                ));
            }
            if !u.values().iter().all(|v| v.is_finite()) {
                return Err(format!(
                    "[[steps]] #{n}: dirichlet.{name}: values must be finite"
                ));
            }
            if let Some(v) = u.values().iter().find(|v| beyond(**v)) {
                return Err(format!(
                    "[[steps]] #{n}: dirichlet.{} = {} is beyond ±{MAX_MAGNITUDE:e}: products with it would overflow; change the units",
                    shorten(name),
                    num(*v)
                ));
            }
        }
    }
    Ok(())
}

fn check_output(f: &RawFile) -> Check {
    if let Some(k) = f.output.reference_step {
        let n = f.steps.len().max(1);
        if k == 0 || k > n {
            return Err(format!(
                "[output] reference_step = {k}: load steps count from 1, and the problem has {n} step{}",
                if n == 1 { "" } else { "s" }
            ));
        }
    }
    for (name, p) in &f.output.probes {
        if !p.values().iter().all(|v| v.is_finite()) {
            return Err(format!("[output] probe {name}: coordinates must be finite"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::{NormalKind, Problem};
    use super::*;
    use std::path::Path;

    const HEAD: &str = "[mesh]\nfile = \"m.msh\"\n[materials.a]\nE = 1.0\nnu = 0.3\n";

    fn parse(body: &str) -> Result<ProblemFile, String> {
        Problem::parse(Path::new("p.toml"), &format!("{HEAD}{body}"))
            .map(|p| p.file)
            .map_err(|e| e.to_string())
    }

    /// ν above NU_LOCKING is solved with a warning naming the material,
    /// except in plane stress, which does not lock.
    #[test]
    fn a_nearly_incompressible_material_is_warned_of_where_p1_locks() {
        let text = |nu: f64, plane: &str| {
            format!("[mesh]\nfile = \"m.msh\"\n[model]\nplane = \"{plane}\"\n[materials.rubber]\nE = 1.0\nnu = {nu}\n")
        };
        let warned = |nu: f64, plane: &str| {
            let p = Problem::parse(Path::new("p.toml"), &text(nu, plane)).unwrap();
            warnings(&p.file)
        };
        for plane in ["strain", "axisymmetric"] {
            let w = warned(0.49, plane);
            assert_eq!(w.len(), 1, "{w:?}");
            assert!(
                w[0].contains("[materials.rubber] nu = 0.49") && w[0].contains("lock"),
                "{w:?}"
            );
            assert!(warned(NU_LOCKING, plane).is_empty());
        }
        assert!(warned(0.499, "stress").is_empty());
    }

    #[test]
    fn contact_keys_become_one_typed_entry() {
        let f = parse(
            "[[contact]]\non = \"i\"\nnormals = \"segment\"\nfriction = 0.0\n\
             [[contact]]\nslave = \"s\"\nmaster = \"m\"\ndiscretization = \"mortar\"\nmax_gap = 0.5\nfriction = 2.0\n\
             [[contact]]\nslave = \"t\"\nmaster = \"m\"\nfriction = 0.25\n\
             [[contact]]\nslave = \"u\"\nmaster = \"m\"\ndiscretization = \"nts\"\n",
        )
        .unwrap();
        let want = [
            Contact {
                pair: ContactPair::Conforming {
                    on: "i".into(),
                    normals: NormalKind::Segment,
                },
                // μ = 0 is frictionless (the same results bit for bit).
                friction: FrictionLaw::Frictionless,
            },
            Contact {
                pair: ContactPair::NonMatching(NonMatchingPair {
                    slave: "s".into(),
                    master: "m".into(),
                    max_gap: Some(0.5),
                    discretization: Some(Discretization::Mortar),
                    interference: false,
                }),
                friction: FrictionLaw::Coulomb(2.0),
            },
            Contact {
                pair: ContactPair::NonMatching(NonMatchingPair {
                    slave: "t".into(),
                    master: "m".into(),
                    max_gap: None,
                    // No key: the default, decided with the mesh (fem::pairs).
                    discretization: None,
                    interference: false,
                }),
                friction: FrictionLaw::Coulomb(0.25),
            },
            Contact {
                pair: ContactPair::NonMatching(NonMatchingPair {
                    slave: "u".into(),
                    master: "m".into(),
                    max_gap: None,
                    discretization: Some(Discretization::Nts),
                    interference: false,
                }),
                friction: FrictionLaw::Frictionless,
            },
        ];
        assert_eq!(f.contact, want);
        let f = parse("[[contact]]\non = \"i\"\ntresca = 0.0\n").unwrap();
        // A zero Tresca bound stays a friction law (rows with a zero slip bound).
        assert_eq!(f.contact[0].friction, FrictionLaw::Tresca(0.0));
    }

    #[test]
    fn dirichlet_and_traction_forms_are_typed_and_scaled_by_steps() {
        let f = parse(
            "[[dirichlet]]\non = \"b\"\nu = [1.0, 2.0]\n[[dirichlet]]\non = \"c\"\nuy = 3.0\n\
             [[traction]]\non = \"t\"\npn = -4.0\n[[traction]]\non = \"q\"\np = [5.0, 6.0]\n\
             [[steps]]\nfactor = 2.0\ndirichlet = { c = [7.0, 8.0] }\n",
        )
        .unwrap();
        assert_eq!(f.dirichlet[0].value, Prescribed::All([1.0, 2.0].into()));
        assert_eq!(f.dirichlet[1].value.components(), [None, Some(3.0), None]);
        assert_eq!(f.traction[0].load, TractionLoad::Normal(-4.0));
        let s = f.at_step(0);
        assert_eq!(s.dirichlet[0].value, Prescribed::All([2.0, 4.0].into()));
        // Explicit step values replace the given component only.
        assert_eq!(s.dirichlet[1].value.components(), [None, Some(8.0), None]);
        assert_eq!(s.traction[0].load, TractionLoad::Normal(-8.0));
        assert_eq!(
            s.traction[1].load,
            TractionLoad::Vector([10.0, 12.0].into())
        );
    }

    #[test]
    fn a_pair_given_twice_is_refused_naming_both_entries() {
        for (a, b) in [
            ("on = \"i\"\nfriction = 0.3", "on = \"i\""),
            (
                "slave = \"s\"\nmaster = \"m\"",
                "slave = \"s\"\nmaster = \"m\"\ndiscretization = \"mortar\"",
            ),
            (
                "slave = \"s\"\nmaster = \"m\"",
                "slave = \"m\"\nmaster = \"s\"",
            ),
        ] {
            let e = parse(&format!(
                "[[contact]]\non = \"x\"\n[[contact]]\n{a}\n[[contact]]\n{b}\n"
            ))
            .unwrap_err();
            assert!(
                e.starts_with("p.toml: [[contact]] #2 (")
                    && e.contains(" and #3 (")
                    && e.contains("same curves"),
                "{a} / {b}: {e}"
            );
        }
        // One slave against two masters, and two slaves on one master, stay allowed.
        parse("[[contact]]\nslave = \"s\"\nmaster = \"m\"\n[[contact]]\nslave = \"s\"\nmaster = \"n\"\n[[contact]]\nslave = \"t\"\nmaster = \"m\"\n")
            .unwrap();
    }

    #[test]
    fn friction_bounds_and_keys_of_the_other_form_are_named() {
        for (keys, want) in [
            (
                "on = \"i\"\ntresca = 1e307",
                "#1 (on = \"i\"): tresca = 1e307 is beyond",
            ),
            ("on = \"i\"\nfriction = 1e101", "friction = 1e101 is beyond"),
            (
                "on = \"i\"\nfriction = -0.0001",
                "friction = -0.0001 must be",
            ),
            (
                "on = \"i\"\nmax_gap = 1.0",
                "max_gap applies to non-matching",
            ),
            (
                "slave = \"s\"\nmaster = \"m\"\nnormals = \"averaged\"",
                "normals applies to conforming",
            ),
            (
                "slave = \"s\"\nmaster = \"m\"\nmax_gap = -1.0",
                "max_gap = -1 must be >= 0",
            ),
            (
                "on = \"i\"\ntresca = 1.0\n[[contact]]\non = \"j\"\nfriction = 0.5",
                "#1 (on = \"i\") has tresca = s and #2 (on = \"j\") friction",
            ),
        ] {
            let e = parse(&format!("[[contact]]\n{keys}\n")).unwrap_err();
            assert!(
                e.contains(want) && e.contains("[[contact]] #1"),
                "{keys}: {e}"
            );
        }
        // The largest accepted values, and an unlimited max_gap.
        parse("[[contact]]\non = \"i\"\ntresca = 1e100\n").unwrap();
        parse("[[contact]]\nslave = \"s\"\nmaster = \"m\"\nfriction = 1e100\nmax_gap = inf\n")
            .unwrap();
    }
}
