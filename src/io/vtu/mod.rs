//! ParaView output: XML UnstructuredGrid (`.vtu`) files and the `.pvd`
//! collection of a time series.
//!
//! Uncompressed files store their arrays as raw little-endian binary in
//! `<AppendedData encoding="raw">` (`header_type="UInt64"`), streamed
//! straight into the file (`stream_appended`): no base64 pass and a third
//! fewer bytes than inline base64, which at 400 k nodes and several load
//! steps is most of a step's write time. With `compress` the arrays are
//! inline base64 and zlib-compressed (`vtkZLibDataCompressor`, level 6),
//! through vtkio. Floating-point arrays are Float64, so values read back
//! bit-exactly; the attributes (ranges, component names) are those vtkio
//! writes (a test holds the two to that).

use std::io::{BufWriter, Write};
use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, VertexNumbers, Vtk,
};

use super::atomic::{write_atomic, write_atomic_with, IoError};
use crate::output::{OutMesh, StepOutput};

/// zlib level used when compression is requested (1 fastest … 9 smallest).
const ZLIB_LEVEL: u32 = 6;

/// One data array read back from a `.vtu` file.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuArray {
    pub name: String,
    pub num_comp: usize,
    /// All values, component-interleaved, converted to f64.
    pub values: Vec<f64>,
}

/// What a `.vtu` file contains, for tests and checks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VtuSummary {
    pub num_points: usize,
    pub num_cells: usize,
    /// Point coordinates, 3 per point.
    pub points: Vec<f64>,
    /// Cell connectivity (point indices) and end offsets.
    pub connectivity: Vec<u64>,
    pub offsets: Vec<u64>,
    /// VTK cell type codes (5 = triangle, 3 = line).
    pub cell_types: Vec<u8>,
    pub point_data: Vec<VtuArray>,
    pub cell_data: Vec<VtuArray>,
}

impl VtuSummary {
    pub fn point_array(&self, name: &str) -> Option<&VtuArray> {
        self.point_data.iter().find(|a| a.name == name)
    }
    pub fn cell_array(&self, name: &str) -> Option<&VtuArray> {
        self.cell_data.iter().find(|a| a.name == name)
    }
}

fn check_len(path: &Path, what: &str, got: usize, want: usize) -> Result<(), IoError> {
    if got == want {
        Ok(())
    } else {
        Err(IoError::format(
            path,
            format!("{what} has {got} entries, expected {want}"),
        ))
    }
}

fn check_index(path: &Path, what: &str, idx: usize, n: usize) -> Result<(), IoError> {
    if idx < n {
        Ok(())
    } else {
        Err(IoError::format(
            path,
            format!("{what}: point index {idx} out of range (have {n} points)"),
        ))
    }
}

fn points3(points: &[[f64; 2]]) -> IOBuffer {
    IOBuffer::F64(points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect())
}

fn array(name: &str, elem: ElementType, data: IOBuffer) -> Attribute {
    Attribute::DataArray(DataArray {
        name: name.to_string(),
        elem,
        data,
    })
}

fn f64_array(name: &str, num_comp: u32, data: Vec<f64>) -> Attribute {
    array(name, ElementType::Generic(num_comp), IOBuffer::F64(data))
}

fn i32_array(name: &str, data: impl Iterator<Item = i64>) -> Attribute {
    // Values are body/material/interface numbers or 0/1 flags; saturate rather than panic.
    let v: Vec<i32> = data.map(|x| i32::try_from(x).unwrap_or(i32::MAX)).collect();
    array(name, ElementType::Generic(1), IOBuffer::I32(v))
}

mod encode;
use encode::*;

/// The arrays of a bulk VTU that depend on the mesh only (`body`,
/// `contact_role`, `material`, the points and the cells), encoded once for
/// the files of a series of load steps: each step then encodes its own
/// fields only ([`write_vtu_with`]), and writes the same bytes.
pub struct VtuMeshParts {
    n: usize,
    m: usize,
    body: OwnedArr,
    contact_role: OwnedArr,
    material: OwnedArr,
    /// Points, connectivity, offsets, types.
    geometry: [OwnedArr; 4],
}

impl VtuMeshParts {
    /// The encoded mesh arrays of `mesh` (uncompressed files only).
    pub fn new(mesh: &OutMesh) -> VtuMeshParts {
        let enc = |a: &Attribute| -> OwnedArr {
            let arrs = data_arrs(std::slice::from_ref(a), COMPONENT_NAMES);
            // The types are the ones Slice takes.
            match arrs.ok().and_then(|mut v| v.pop()) {
                Some(a) => a.to_owned_arr(),
                None => unreachable!("mesh arrays are Int32"),
            }
        };
        let points = points3(&mesh.points);
        let cells = bulk_cells(mesh);
        let VertexNumbers::XML {
            connectivity,
            offsets,
        } = &cells.cell_verts
        else {
            unreachable!("bulk_cells builds XML cells")
        };
        let types: Vec<u8> = cells.types.iter().map(|&t| t as u8).collect();
        let IOBuffer::F64(pts) = &points else {
            unreachable!("points3 builds f64")
        };
        let g = |name, ncomp, s| Arr::new(name, ncomp, s, COMPONENT_NAMES, false).to_owned_arr();
        VtuMeshParts {
            n: mesh.points.len(),
            m: mesh.triangles.len(),
            body: enc(&body_array(mesh)),
            contact_role: enc(&i32_array("contact_role", contact_roles(mesh).into_iter())),
            material: enc(&material_array(mesh)),
            geometry: [
                g("Points", 3, Slice::F64(pts)),
                g("connectivity", 1, Slice::U64(connectivity)),
                g("offsets", 1, Slice::U64(offsets)),
                g("types", 1, Slice::U8(&types)),
            ],
        }
    }
}

fn body_array(mesh: &OutMesh) -> Attribute {
    i32_array("body", mesh.point_body.iter().map(|&b| i64::from(b)))
}

fn material_array(mesh: &OutMesh) -> Attribute {
    i32_array("material", mesh.material.iter().map(|&k| i64::from(k)))
}

/// The triangles as VTK cells.
fn bulk_cells(mesh: &OutMesh) -> Cells {
    let m = mesh.triangles.len();
    let connectivity: Vec<u64> = mesh
        .triangles
        .iter()
        .flat_map(|t| t.iter().map(|&i| i as u64))
        .collect();
    let offsets: Vec<u64> = (1..=m as u64).map(|k| 3 * k).collect();
    Cells {
        cell_verts: VertexNumbers::XML {
            connectivity,
            offsets,
        },
        types: vec![CellType::Triangle; m],
    }
}

/// Writes the bulk mesh with its step fields (see the module doc for the encoding).
///
/// Point data: `displacement` (3 components, z = 0), `body`,
/// `contact_role` (0 none, 1 conforming pair, 2 slave, 3 master), and
/// `reaction` (3 components) when the step has one. Cell data:
/// `stress` (σxx, σyy, σxy, and σzz in plane strain), `von_mises`,
/// `principal_stress` (2), `material`. With a reference step, point data
/// `displacement_change` and cell data `stress_change` too. Points are the
/// undeformed coordinates with z = 0.
pub fn write_vtu(
    path: &Path,
    mesh: &OutMesh,
    step: &StepOutput,
    compress: bool,
) -> Result<(), IoError> {
    write_vtu_with(path, mesh, step, compress, None)
}

/// [`write_vtu`] with the mesh arrays encoded once (`parts` of this mesh;
/// used for uncompressed files): the same bytes, the step's fields alone
/// encoded.
pub fn write_vtu_with(
    path: &Path,
    mesh: &OutMesh,
    step: &StepOutput,
    compress: bool,
    parts: Option<&VtuMeshParts>,
) -> Result<(), IoError> {
    let n = mesh.points.len();
    let m = mesh.triangles.len();
    check_len(path, "point_body", mesh.point_body.len(), n)?;
    check_len(path, "material", mesh.material.len(), m)?;
    check_len(path, "displacement", step.displacement.len(), n)?;
    check_len(path, "stress", step.stress.len(), m)?;
    check_len(path, "von_mises", step.von_mises.len(), m)?;
    check_len(path, "principal", step.principal.len(), m)?;
    let names = mesh.kind.component_names();
    for t in &mesh.triangles {
        for &i in t {
            check_index(path, "triangle", i, n)?;
        }
    }
    if let Some(c) = &step.change {
        check_len(path, "displacement_change", c.displacement.len(), n)?;
        check_len(path, "stress_change", c.stress.len(), m)?;
    }
    let vec3 = |v: &[[f64; 2]]| -> Vec<f64> { v.iter().flat_map(|u| [u[0], u[1], 0.0]).collect() };
    let ncomp: usize = mesh.kind.stress_len();
    let has_reaction = step.reaction.len() == n;
    if let Some(p) = parts.filter(|p| !compress && p.n == n && p.m == m) {
        // The step's fields straight from the step where they lie as
        // written (stress with 4 components, von Mises, principal
        // stresses); the 3-component vectors padded with z = 0.
        fn stress_vals(s: &[[f64; 4]], ncomp: usize) -> std::borrow::Cow<'_, [f64]> {
            if ncomp == 4 {
                std::borrow::Cow::Borrowed(s.as_flattened())
            } else {
                std::borrow::Cow::Owned(s.iter().flat_map(|s| s[..ncomp].to_vec()).collect())
            }
        }
        fn f<'a>(name: &str, k: u32, v: &'a [f64], names: Names, vectors: bool) -> Arr<'a> {
            Arr::new(name, k, Slice::F64(v), names, vectors)
        }
        let stress = stress_vals(&step.stress, ncomp);
        let change = step
            .change
            .as_ref()
            .map(|c| (vec3(&c.displacement), stress_vals(&c.stress, ncomp)));
        fn xy0<'a>(name: &str, v: &'a [[f64; 2]], names: Names) -> Arr<'a> {
            Arr::new(name, 3, Slice::Xy0(v), names, true)
        }
        let u = xy0("displacement", &step.displacement, names);
        let reaction = has_reaction.then(|| xy0("reaction", &step.reaction, names));
        let stress = f("stress", ncomp as u32, &stress, names, false);
        let von_mises = f("von_mises", 1, &step.von_mises, names, false);
        let principal = f(
            "principal_stress",
            2,
            step.principal.as_flattened(),
            names,
            false,
        );
        let change = change.as_ref().map(|(du, ds)| {
            (
                f("displacement_change", 3, du, names, true),
                f("stress_change", ncomp as u32, ds, names, false),
            )
        });
        let point: Vec<ArrRef> = [
            Some(u.by_ref()),
            Some(p.body.by_ref()),
            Some(p.contact_role.by_ref()),
            reaction.as_ref().map(Arr::by_ref),
            change.as_ref().map(|c| c.0.by_ref()),
        ]
        .into_iter()
        .flatten()
        .collect();
        let cell: Vec<ArrRef> = [
            Some(stress.by_ref()),
            Some(von_mises.by_ref()),
            Some(principal.by_ref()),
            Some(p.material.by_ref()),
            change.as_ref().map(|c| c.1.by_ref()),
        ]
        .into_iter()
        .flatten()
        .collect();
        let geometry: Vec<ArrRef> = p.geometry.iter().map(OwnedArr::by_ref).collect();
        return write_atomic(path, |tmp| {
            let file = super::atomic::create_new(tmp)
                .map_err(|e| IoError::io(path, "cannot create", e))?;
            let mut w = BufWriter::with_capacity(1 << 20, file);
            stream_appended(&mut w, n, m, &point, &cell, &geometry)
                .and_then(|()| w.flush())
                .map_err(|e| IoError::io(path, "cannot write", e))
        });
    }
    let stress_of = |s: &[[f64; 4]]| -> Vec<f64> {
        s.iter().flat_map(|s| s[..ncomp].iter().copied()).collect()
    };
    let displacement = array(
        "displacement",
        ElementType::Vectors,
        IOBuffer::F64(vec3(&step.displacement)),
    );
    let mut point = vec![
        displacement,
        body_array(mesh),
        i32_array("contact_role", contact_roles(mesh).into_iter()),
    ];
    let mut cell = vec![
        f64_array("stress", ncomp as u32, stress_of(&step.stress)),
        f64_array("von_mises", 1, step.von_mises.clone()),
        f64_array(
            "principal_stress",
            2,
            step.principal.iter().flat_map(|p| [p[0], p[1]]).collect(),
        ),
        material_array(mesh),
    ];
    if has_reaction {
        point.push(array(
            "reaction",
            ElementType::Vectors,
            IOBuffer::F64(vec3(&step.reaction)),
        ));
    }
    if let Some(c) = &step.change {
        point.push(array(
            "displacement_change",
            ElementType::Vectors,
            IOBuffer::F64(vec3(&c.displacement)),
        ));
        cell.push(f64_array(
            "stress_change",
            ncomp as u32,
            stress_of(&c.stress),
        ));
    }
    let piece = UnstructuredGridPiece {
        points: points3(&mesh.points),
        cells: bulk_cells(mesh),
        data: Attributes { point, cell },
    };
    write_piece(path, piece, compress, names)
}

/// Writes a solved solid model (VTK tetrahedra, type 10). Point data:
/// `displacement` (3), `body`; cell data: `stress` (six components in
/// VTK's symmetric-tensor order xx, yy, zz, xy, yz, xz), `von_mises`,
/// `principal_stress` (3), `material`.
pub fn write_solid_vtu(
    path: &Path,
    out: &crate::output::SolidOutput,
    compress: bool,
) -> Result<(), IoError> {
    let (n, m) = (out.points.len(), out.tets.len());
    check_len(path, "point_body", out.point_body.len(), n)?;
    check_len(path, "displacement", out.displacement.len(), n)?;
    check_len(path, "material", out.material.len(), m)?;
    check_len(path, "stress", out.stress.len(), m)?;
    check_len(path, "von_mises", out.von_mises.len(), m)?;
    check_len(path, "principal", out.principal.len(), m)?;
    for t in &out.tets {
        for &i in t {
            check_index(path, "tetrahedron", i, n)?;
        }
    }
    let cells = Cells {
        cell_verts: VertexNumbers::XML {
            connectivity: out.tets.iter().flatten().map(|&i| i as u64).collect(),
            offsets: (1..=m as u64).map(|k| 4 * k).collect(),
        },
        types: vec![CellType::Tetra; m],
    };
    if !out.reaction.is_empty() {
        check_len(path, "reaction", out.reaction.len(), n)?;
    }
    if let Some(c) = &out.change {
        check_len(path, "displacement_change", c.displacement.len(), n)?;
        check_len(path, "stress_change", c.stress.len(), m)?;
    }
    let mut point = vec![
        array(
            "displacement",
            ElementType::Vectors,
            IOBuffer::F64(out.displacement.as_flattened().to_vec()),
        ),
        i32_array("body", out.point_body.iter().map(|&b| i64::from(b))),
    ];
    if !out.reaction.is_empty() {
        point.push(array(
            "reaction",
            ElementType::Vectors,
            IOBuffer::F64(out.reaction.as_flattened().to_vec()),
        ));
    }
    let mut cell = vec![
        f64_array("stress", 6, out.stress.as_flattened().to_vec()),
        f64_array("von_mises", 1, out.von_mises.clone()),
        f64_array("principal_stress", 3, out.principal.as_flattened().to_vec()),
        i32_array("material", out.material.iter().map(|&k| i64::from(k))),
    ];
    if let Some(c) = &out.change {
        point.push(array(
            "displacement_change",
            ElementType::Vectors,
            IOBuffer::F64(c.displacement.as_flattened().to_vec()),
        ));
        cell.push(f64_array(
            "stress_change",
            6,
            c.stress.as_flattened().to_vec(),
        ));
    }
    let piece = UnstructuredGridPiece {
        points: IOBuffer::F64(out.points.as_flattened().to_vec()),
        cells,
        data: Attributes { point, cell },
    };
    let names = crate::fem::ElementKind::Solid.component_names();
    write_piece(path, piece, compress, names)
}

/// Writes the contact surface of a solid model (VTK triangles, type 5, on
/// one point per contact row). Point data: `contact_pressure`, `gap`,
/// `active` (Int32 0/1), `normal` (3), `multiplier`, `interface` (Int32),
/// `gap0`. With no contact rows a valid empty grid is written.
pub fn write_solid_contact_vtu(
    path: &Path,
    c: &crate::output::SolidContactOutput,
    compress: bool,
) -> Result<(), IoError> {
    let n = c.points.len();
    for (what, len) in [
        ("normal", c.normal.len()),
        ("interface", c.interface.len()),
        ("gap0", c.gap0.len()),
        ("gap", c.gap.len()),
        ("multiplier", c.multiplier.len()),
        ("contact_pressure", c.pressure.len()),
        ("active", c.active.len()),
    ] {
        check_len(path, what, len, n)?;
    }
    for t in &c.triangles {
        for &i in t {
            check_index(path, "contact triangle", i, n)?;
        }
    }
    let m = c.triangles.len();
    let cells = Cells {
        cell_verts: VertexNumbers::XML {
            connectivity: c.triangles.iter().flatten().map(|&i| i as u64).collect(),
            offsets: (1..=m as u64).map(|k| 3 * k).collect(),
        },
        types: vec![CellType::Triangle; m],
    };
    let mut point = vec![
        f64_array("contact_pressure", 1, c.pressure.clone()),
        f64_array("gap", 1, c.gap.clone()),
        i32_array("active", c.active.iter().map(|&a| i64::from(a))),
        array(
            "normal",
            ElementType::Vectors,
            IOBuffer::F64(c.normal.as_flattened().to_vec()),
        ),
        f64_array("multiplier", 1, c.multiplier.clone()),
        i32_array("interface", c.interface.iter().map(|&k| i64::from(k))),
        f64_array("gap0", 1, c.gap0.clone()),
    ];
    if !c.pressure_change.is_empty() {
        check_len(path, "contact_pressure_change", c.pressure_change.len(), n)?;
        point.push(f64_array(
            "contact_pressure_change",
            1,
            c.pressure_change.clone(),
        ));
    }
    // Friction (docs/methods.md §12.6): 3-vectors in global coordinates
    // and the state, as 2D's names.
    if !c.friction_state.is_empty() {
        check_len(path, "tangential_traction", c.tangential_traction.len(), n)?;
        check_len(path, "slip", c.slip.len(), n)?;
        check_len(path, "state", c.friction_state.len(), n)?;
        for (name, v) in [
            ("tangential_traction", &c.tangential_traction),
            ("slip", &c.slip),
        ] {
            point.push(array(
                name,
                ElementType::Vectors,
                IOBuffer::F64(v.as_flattened().to_vec()),
            ));
        }
        point.push(i32_array(
            "state",
            c.friction_state.iter().map(|&a| i64::from(a)),
        ));
    }
    let piece = UnstructuredGridPiece {
        points: IOBuffer::F64(c.points.as_flattened().to_vec()),
        cells,
        data: Attributes {
            point,
            cell: vec![],
        },
    };
    let names = crate::fem::ElementKind::Solid.component_names();
    write_piece(path, piece, compress, names)
}

/// Each point's part in the contact: 0 none, 1 a conforming pair, 2 a
/// slave node, 3 a master node (a point both slave and master gets 2).
fn contact_roles(mesh: &OutMesh) -> Vec<i64> {
    let c = &mesh.contact;
    let mut role = vec![0i64; mesh.points.len()];
    for (r, &first) in c.first.iter().enumerate() {
        let nm = c.nonmatching.get(r).copied().unwrap_or(false);
        if let Some(x) = role.get_mut(first) {
            *x = if nm { 2 } else { 1 };
        }
        for &(p, w) in &c.second[r] {
            if let Some(x) = role.get_mut(p) {
                if nm && (w != 0.0 || *x == 0) && *x != 2 {
                    *x = 3;
                } else if !nm && w != 0.0 {
                    *x = 1;
                }
            }
        }
    }
    role
}

/// Writes the contact boundary: one point per constraint row
/// (`mesh.contact.points`), `mesh.contact.segments` as line cells.
///
/// Point data: `contact_pressure`, `gap`, `active` (Int32 0/1), `normal`
/// (3 components, z = 0), `multiplier`, `interface` (Int32), `tangent`
/// (n rotated by +90°: the direction of increasing arc length along a
/// counter-clockwise boundary of the first side), `role` (1 conforming,
/// 2 slave), and `contact_pressure_change` with a reference step. With no
/// contact rows a valid empty grid is written.
pub fn write_contact_vtu(
    path: &Path,
    mesh: &OutMesh,
    step: &StepOutput,
    compress: bool,
) -> Result<(), IoError> {
    write_contact_vtu_with_friction(path, mesh, step, None, compress)
}

/// The friction arrays of the contact VTU, one value per contact row
/// (docs/problem-format.md §6): the tangential traction λ_t / (tributary
/// length × thickness) (Pa), the slip of the step (tangential relative
/// displacement increment) (m) and the state (0 open, 1 stick, 2 slip).
pub struct FrictionArrays<'a> {
    pub tangential_traction: &'a [f64],
    pub slip: &'a [f64],
    pub state: &'a [u8],
}

/// [`write_contact_vtu`] with the friction arrays `tangential_traction`,
/// `slip` and `state` (Int32) when `friction` is given.
pub fn write_contact_vtu_with_friction(
    path: &Path,
    mesh: &OutMesh,
    step: &StepOutput,
    friction: Option<&FrictionArrays>,
    compress: bool,
) -> Result<(), IoError> {
    let c = &mesh.contact;
    let r = c.points.len();
    check_len(path, "contact normal", c.normal.len(), r)?;
    check_len(path, "contact interface", c.interface.len(), r)?;
    check_len(path, "multipliers", step.multipliers.len(), r)?;
    check_len(path, "contact_pressure", step.contact_pressure.len(), r)?;
    check_len(path, "gap", step.gap.len(), r)?;
    check_len(path, "active", step.active.len(), r)?;
    for s in &c.segments {
        for &i in s {
            check_index(path, "contact segment", i, r)?;
        }
    }

    let k = c.segments.len();
    let connectivity: Vec<u64> = c
        .segments
        .iter()
        .flat_map(|s| [s[0] as u64, s[1] as u64])
        .collect();
    let offsets: Vec<u64> = (1..=k as u64).map(|j| 2 * j).collect();
    let cells = Cells {
        cell_verts: VertexNumbers::XML {
            connectivity,
            offsets,
        },
        types: vec![CellType::Line; k],
    };

    let mut point = vec![
        f64_array("contact_pressure", 1, step.contact_pressure.clone()),
        f64_array("gap", 1, step.gap.clone()),
        i32_array("active", step.active.iter().map(|&a| i64::from(a))),
        f64_array(
            "normal",
            3,
            c.normal.iter().flat_map(|n| [n[0], n[1], 0.0]).collect(),
        ),
        f64_array("multiplier", 1, step.multipliers.clone()),
        i32_array("interface", c.interface.iter().map(|&i| i64::from(i))),
        f64_array(
            "tangent",
            3,
            c.normal.iter().flat_map(|n| [-n[1], n[0], 0.0]).collect(),
        ),
        i32_array(
            "role",
            (0..r).map(|k| {
                if c.nonmatching.get(k).copied().unwrap_or(false) {
                    2
                } else {
                    1
                }
            }),
        ),
    ];

    if let Some(ch) = &step.change {
        check_len(
            path,
            "contact_pressure_change",
            ch.contact_pressure.len(),
            r,
        )?;
        point.push(f64_array(
            "contact_pressure_change",
            1,
            ch.contact_pressure.clone(),
        ));
    }

    if let Some(f) = friction {
        check_len(path, "tangential_traction", f.tangential_traction.len(), r)?;
        check_len(path, "slip", f.slip.len(), r)?;
        check_len(path, "state", f.state.len(), r)?;
        point.push(f64_array(
            "tangential_traction",
            1,
            f.tangential_traction.to_vec(),
        ));
        point.push(f64_array("slip", 1, f.slip.to_vec()));
        point.push(i32_array("state", f.state.iter().map(|&a| i64::from(a))));
    }
    let piece = UnstructuredGridPiece {
        points: points3(&c.points),
        cells,
        data: Attributes {
            point,
            cell: Vec::new(),
        },
    };
    write_piece(path, piece, compress, COMPONENT_NAMES)
}

fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

fn xml_unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// Writes a ParaView collection (`.pvd`): one `DataSet` per entry
/// `(time, file)`, file names as given (normally relative to the `.pvd`).
/// Entries sharing a time get increasing `part` numbers, so a step's bulk
/// and contact files can be listed together.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> Result<(), IoError> {
    let mut text = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (i, (t, file)) in entries.iter().enumerate() {
        if !t.is_finite() {
            return Err(IoError::format(
                path,
                format!("time step {t} of {file:?} is not finite"),
            ));
        }
        let part = entries[..i].iter().filter(|(s, _)| s == t).count();
        text.push_str(&format!(
            "    <DataSet timestep=\"{t:?}\" group=\"\" part=\"{part}\" file=\"{}\"/>\n",
            xml_escape(file)
        ));
    }
    text.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic_with(path, |w| w.write_all(text.as_bytes()))
}

/// Reads the `(timestep, file)` entries of a `.pvd` written by [`write_pvd`]
/// (a minimal reader: it looks only at `<DataSet .../>` elements).
pub fn read_pvd(path: &Path) -> Result<Vec<(f64, String)>, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, "cannot read", e))?;
    if !text.contains("type=\"Collection\"") {
        return Err(IoError::format(path, "not a VTK Collection file"));
    }
    let mut out = Vec::new();
    let mut rest = text.as_str();
    while let Some(start) = rest.find("<DataSet") {
        let after = &rest[start + "<DataSet".len()..];
        let end = after
            .find('>')
            .ok_or_else(|| IoError::format(path, "unterminated <DataSet> element"))?;
        let tag = &after[..end];
        let attr = |name: &str| -> Option<String> {
            let key = format!("{name}=\"");
            let mut from = 0;
            // Match the attribute name at a word boundary.
            while let Some(p) = tag[from..].find(&key) {
                let pos = from + p;
                let boundary =
                    pos == 0 || tag[..pos].chars().last().is_some_and(|c| c.is_whitespace());
                let vstart = pos + key.len();
                if boundary {
                    let vend = tag[vstart..].find('"')?;
                    return Some(xml_unescape(&tag[vstart..vstart + vend]));
                }
                from = vstart;
            }
            None
        };
        let ts =
            attr("timestep").ok_or_else(|| IoError::format(path, "<DataSet> without timestep"))?;
        let t: f64 = ts
            .trim()
            .parse()
            .map_err(|_| IoError::format(path, format!("bad timestep {ts:?}")))?;
        let file = attr("file").ok_or_else(|| IoError::format(path, "<DataSet> without file"))?;
        out.push((t, file));
        rest = &after[end..];
    }
    Ok(out)
}

fn to_f64(path: &Path, name: &str, buf: &IOBuffer) -> Result<Vec<f64>, IoError> {
    buf.cast_into::<f64>()
        .ok_or_else(|| IoError::format(path, format!("array {name:?}: unsupported data type")))
}

fn summarize_attrs(path: &Path, attrs: Vec<Attribute>) -> Result<Vec<VtuArray>, IoError> {
    let mut out = Vec::new();
    for a in attrs {
        match a {
            Attribute::DataArray(d) => {
                let values = to_f64(path, &d.name, &d.data)?;
                out.push(VtuArray {
                    num_comp: d.elem.num_comp() as usize,
                    name: d.name,
                    values,
                });
            }
            Attribute::Field { data_array, .. } => {
                for f in data_array {
                    let values = to_f64(path, &f.name, &f.data)?;
                    out.push(VtuArray {
                        num_comp: f.elem as usize,
                        name: f.name,
                        values,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// Reads a `.vtu` file (one piece) back: counts, points, cells and every
/// point/cell array converted to f64.
pub fn read_vtu_arrays(path: &Path) -> Result<VtuSummary, IoError> {
    let vtk_err = |e: &dyn std::fmt::Display| IoError::Vtk {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    // Files with appended raw data are read as their inline form.
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, "cannot read", e))?;
    let bytes = appended_to_inline(bytes).map_err(|e| vtk_err(&e))?;
    let vtk = Vtk::parse_xml(std::io::Cursor::new(bytes)).map_err(|e| vtk_err(&e))?;
    let pieces = match vtk.data {
        DataSet::UnstructuredGrid { pieces, .. } => pieces,
        _ => return Err(IoError::format(path, "not an UnstructuredGrid")),
    };
    let piece = match pieces.into_iter().next() {
        Some(p) => p.into_loaded_piece_data(None).map_err(|e| vtk_err(&e))?,
        None => return Err(IoError::format(path, "UnstructuredGrid has no piece")),
    };
    let num_points = piece.num_points();
    let num_cells = piece.cells.types.len();
    let points = to_f64(path, "Points", &piece.points)?;
    let (connectivity, offsets) = piece.cells.cell_verts.into_xml();
    let cell_types = piece.cells.types.iter().map(|&t| t as u8).collect();
    Ok(VtuSummary {
        num_points,
        num_cells,
        points,
        connectivity,
        offsets,
        cell_types,
        point_data: summarize_attrs(path, piece.data.point)?,
        cell_data: summarize_attrs(path, piece.data.cell)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn piece(np: usize, nc: usize, cell_data: bool) -> UnstructuredGridPiece {
        let points: Vec<[f64; 2]> = (0..np)
            .map(|i| [0.1 * i as f64, -(i as f64).sqrt()])
            .collect();
        let mut point = vec![];
        if np > 0 {
            point.push(array(
                "displacement",
                ElementType::Vectors,
                IOBuffer::F64((0..3 * np).map(|i| (i as f64 * 0.7).sin() * 1e-3).collect()),
            ));
            point.push(i32_array("body", (0..np as i64).map(|i| i % 3)));
            point.push(f64_array(
                "gap",
                1,
                (0..np).map(|i| 1e-20 * i as f64).collect(),
            ));
            point.push(f64_array("normal", 3, vec![f64::NAN; 3 * np]));
        }
        let cell = if cell_data {
            vec![
                f64_array(
                    "stress",
                    4,
                    (0..4 * nc).map(|i| -3.5e9 + 1e7 * i as f64).collect(),
                ),
                i32_array("material", (0..nc as i64).map(|i| -i)),
            ]
        } else {
            vec![]
        };
        let connectivity: Vec<u64> = (0..3 * nc as u64).map(|k| k % np.max(1) as u64).collect();
        UnstructuredGridPiece {
            points: points3(&points),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity,
                    offsets: (1..=nc as u64).map(|k| 3 * k).collect(),
                },
                types: vec![CellType::Triangle; nc],
            },
            data: Attributes { point, cell },
        }
    }

    /// The streamed file (arrays appended raw), with its arrays put back
    /// inline in base64, is byte for byte the one vtkio writes (counts,
    /// ranges, component names, empty sections, NaN): the same arrays and
    /// attributes, only stored otherwise; and it reads back.
    #[test]
    fn streamed_vtu_is_vtkio_bytes() {
        for (np, nc, cd) in [
            (7, 5, true),
            (40, 0, false),
            (0, 0, false),
            (1, 1, true),
            (5, 3, false),
        ] {
            let p = piece(np, nc, cd);
            let want = vtkio_bytes(p.clone(), false, COMPONENT_NAMES).unwrap();
            let mut got = vec![];
            stream_piece(&mut got, &p, COMPONENT_NAMES).unwrap();
            assert!(
                got.windows(29)
                    .any(|w| w == b"<AppendedData encoding=\"raw\">"),
                "np {np} nc {nc}: not appended raw"
            );
            let got = appended_to_inline(got).unwrap();
            assert!(
                got == want,
                "np {np} nc {nc}:\n{}\n{}",
                String::from_utf8_lossy(&got),
                String::from_utf8_lossy(&want)
            );
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.vtu");
        write_piece(&path, piece(9, 4, true), false, COMPONENT_NAMES).unwrap();
        bulk_with_parts_is_the_same_file(dir.path());
        let back = read_vtu_arrays(&path).unwrap();
        assert_eq!((back.num_points, back.num_cells), (9, 4));
        let s = back.cell_array("stress").unwrap();
        assert_eq!(s.values[5], -3.5e9 + 5e7);
    }

    /// A bulk VTU written with the mesh arrays encoded once
    /// ([`VtuMeshParts`]) is byte for byte the one written without, with
    /// and without reactions and change fields, in plane strain and stress.
    fn bulk_with_parts_is_the_same_file(dir: &Path) {
        let mesh = OutMesh {
            points: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
            point_tags: vec![1, 2, 3, 4],
            point_body: vec![0, 0, 1, 1],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
            material: vec![0, 1],
            material_names: vec!["a".into(), "b".into()],
            kind: crate::fem::ElementKind::PlaneStrain,
            contact: Default::default(),
        };
        let mut step = StepOutput {
            displacement: vec![[1e-3, -2e-3], [0.5, 0.25], [-0.0, 3.0], [7.0, 1e-300]],
            stress: vec![[1.0, 2.0, 3.0, 4.0], [-5.0, 6.5, f64::NAN, 0.0]],
            von_mises: vec![2.0, 3.0],
            principal: vec![[1.0, -1.0], [2.0, 0.5]],
            ..Default::default()
        };
        for k in 0..4 {
            let mut mesh = mesh.clone();
            mesh.kind = if k % 2 == 0 {
                crate::fem::ElementKind::PlaneStrain
            } else {
                crate::fem::ElementKind::PlaneStress { thickness: 1.0 }
            };
            if k >= 2 {
                step.reaction = vec![[1.0, 2.0]; 4];
                step.change = Some(crate::output::Change {
                    reference_step: 1,
                    displacement: vec![[0.125, -0.5]; 4],
                    stress: vec![[9.0; 4]; 2],
                    contact_pressure: vec![],
                });
            }
            let parts = VtuMeshParts::new(&mesh);
            let (a, b) = (dir.join(format!("a{k}.vtu")), dir.join(format!("b{k}.vtu")));
            write_vtu(&a, &mesh, &step, false).unwrap();
            write_vtu_with(&b, &mesh, &step, false, Some(&parts)).unwrap();
            let (a, b) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
            assert!(
                a == b,
                "k {k}:\n{}\n{}",
                String::from_utf8_lossy(&a),
                String::from_utf8_lossy(&b)
            );
        }
    }
}
