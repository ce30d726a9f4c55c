//! `signorini mesh model.geo`: run Gmsh (2D, MSH 4.1) and check the result
//! with our own reader, so a mesh that signorini cannot read fails here.

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
    let result = crate::io::atomic::write_atomic(&out, |tmp| {
        let mut cmd = Command::new(&a.gmsh);
        cmd.arg("-2").arg("-format").arg("msh41");
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
                crate::outln!(
                    "{}: {} nodes, {} triangles",
                    out.display(),
                    m.nodes.len(),
                    m.triangles.len()
                );
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
