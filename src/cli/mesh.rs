//! `signorini mesh model.geo`: run Gmsh (MSH 4.1) and check the result
//! with our own reader, so a mesh that signorini cannot read fails here.
//! A .geo that declares a `Physical Volume` is a 3D model (its volumes are
//! the materials, docs/problem-format.md §12) and is meshed with `-3`;
//! `--dim` overrides the guess.

use clap::Args;
use std::path::PathBuf;
use std::process::Command;

#[derive(Args, Debug, Clone)]
pub struct MeshArgs {
    /// The Gmsh geometry file.
    pub geo: PathBuf,
    /// Output mesh (default: the .geo with extension .msh).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write binary MSH 4.1 instead of ASCII.
    #[arg(long)]
    pub binary: bool,
    /// The Gmsh executable.
    #[arg(long, default_value = "gmsh")]
    pub gmsh: String,
    /// Mesh in 2D (triangles) or 3D (tetrahedra); default: 3 when the .geo
    /// declares a Physical Volume, else 2.
    #[arg(long, value_parser = clap::value_parser!(u8).range(2..=3))]
    pub dim: Option<u8>,
}

/// Whether the Gmsh geometry `text` declares a `Physical Volume` (outside
/// comments): the mark of a 3D model, whose materials are volumes.
pub fn declares_volume(text: &str) -> bool {
    let mut code = String::with_capacity(text.len());
    let mut rest = text;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.find('\n').map_or("", |i| &r[i..]);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.find("*/").map_or("", |i| &r[i + 2..]);
        } else {
            let c = rest.chars().next().unwrap_or(' ');
            code.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    let words: Vec<&str> = code
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .collect();
    words.windows(2).any(|w| w == ["Physical", "Volume"])
}

pub fn run(a: &MeshArgs, quiet: bool) -> i32 {
    if !a.geo.is_file() {
        crate::errln!("error: {}: no such file", a.geo.display());
        return 2;
    }
    if Command::new(&a.gmsh).arg("--version").output().is_err() {
        crate::errln!(
            "error: Gmsh is not installed (`{}` not found); on Debian: apt-get install gmsh (or pass --gmsh PATH)",
            a.gmsh
        );
        return 2;
    }
    let out = a
        .output
        .clone()
        .unwrap_or_else(|| a.geo.with_extension("msh"));
    let dim = match a.dim {
        Some(d) => d,
        None => match std::fs::read(&a.geo) {
            Ok(b) if declares_volume(&String::from_utf8_lossy(&b)) => 3,
            _ => 2,
        },
    };
    let result = crate::io::atomic::write_atomic(&out, |tmp| {
        let mut cmd = Command::new(&a.gmsh);
        cmd.arg(format!("-{dim}")).arg("-format").arg("msh41");
        if a.binary {
            cmd.arg("-bin");
        }
        cmd.arg(&a.geo).arg("-o").arg(tmp);
        let o = cmd.output().map_err(|cause| crate::io::IoError::Io {
            path: out.clone(),
            action: "run gmsh",
            cause,
        })?;
        if !o.status.success() || !tmp.is_file() {
            let err = String::from_utf8_lossy(&o.stderr);
            let tail: Vec<&str> = err
                .lines()
                .filter(|l| !l.trim().is_empty())
                .rev()
                .take(3)
                .collect();
            return Err(crate::io::IoError::Format {
                path: a.geo.clone(),
                message: format!(
                    "gmsh failed: {}",
                    tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
                ),
            });
        }
        Ok(())
    });
    if let Err(e) = result {
        crate::errln!("error: {e}");
        return 2;
    }
    match crate::mesh::read_msh(&out) {
        Ok(m) => {
            if !quiet {
                let groups: Vec<String> = m
                    .groups
                    .iter()
                    .map(|g| {
                        format!(
                            "{} ({}, {})",
                            g.name,
                            crate::fem::topology::dim_name(g.dim),
                            g.elements.len()
                        )
                    })
                    .collect();
                if m.dim() == 3 {
                    crate::outln!(
                        "{}: {} nodes, {} tetrahedra, {} boundary triangles (3D)",
                        out.display(),
                        m.nodes.len(),
                        m.tets.len(),
                        m.triangles.len()
                    );
                } else {
                    crate::outln!(
                        "{}: {} nodes, {} triangles",
                        out.display(),
                        m.nodes.len(),
                        m.triangles.len()
                    );
                }
                crate::outln!("physical groups: {}", groups.join(", "));
            }
            0
        }
        Err(e) => {
            crate::errln!("error: {e}");
            2
        }
    }
}

#[cfg(test)]
mod tests {
    use super::declares_volume;

    #[test]
    fn a_physical_volume_outside_comments_makes_a_3d_geo() {
        assert!(declares_volume(
            "Box(1) = {0,0,0,1,1,1};\nPhysical  Volume(\"a\") = {1};"
        ));
        assert!(declares_volume("Physical\nVolume(1) = {1};"));
        assert!(!declares_volume("Physical Surface(\"a\") = {1};"));
        assert!(!declares_volume(
            "// Physical Volume(\"a\") = {1};\nPoint(1) = {0,0,0};"
        ));
        assert!(!declares_volume("/* Physical Volume(1) = {1}; */"));
    }
}
