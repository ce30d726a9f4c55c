//! The problem file as serde reads it: the `[[contact]]`, `[[dirichlet]]`
//! and `[[traction]]` entries with their keys as loose options, exactly as
//! written. `validate` turns them into the typed entries of [`super`] once,
//! so that no consumer has to test which keys are present.

use super::{
    opt_vector, Components, Force, LoadStep, Material, MeshSection, ModelSection, NormalKind,
    OutputSection, Plane, Slip, Units,
};
use crate::qp::SolverSection;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDirichlet {
    pub on: String,
    #[serde(default, deserialize_with = "opt_vector")]
    pub u: Option<Components>,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
    pub uz: Option<f64>,
    pub turn: Option<RawTurn>,
}

/// `turn = { angle, axis, origin }` of a `[[dirichlet]]` as written.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTurn {
    pub angle: f64,
    #[serde(default, deserialize_with = "opt_vector")]
    pub axis: Option<Components>,
    #[serde(default, deserialize_with = "opt_vector")]
    pub origin: Option<Components>,
}

impl RawDirichlet {
    /// Every prescribed value given, in the order u, ux, uy, uz.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.u
            .iter()
            .flat_map(|u| u.values())
            .chain(&self.ux)
            .chain(&self.uy)
            .chain(&self.uz)
            .copied()
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTraction {
    pub on: String,
    #[serde(default, deserialize_with = "opt_vector")]
    pub p: Option<Components>,
    pub pn: Option<f64>,
}

impl RawTraction {
    /// Every traction value given, in the order p, pn.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.p
            .iter()
            .flat_map(|p| p.values())
            .chain(&self.pn)
            .copied()
    }
}

/// `[model]` as written; the keys of a plane model keep where they were
/// written, for a 3D mesh to refuse them naming the line.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawModel {
    plane: Option<toml::Spanned<Plane>>,
    thickness: Option<toml::Spanned<f64>>,
    #[serde(default, deserialize_with = "opt_vector")]
    gravity: Option<Components>,
    omega: Option<toml::Spanned<f64>>,
    units: Option<Units>,
}

impl From<RawModel> for ModelSection {
    fn from(r: RawModel) -> ModelSection {
        let d = ModelSection::default();
        ModelSection {
            plane: r.plane.as_ref().map_or(d.plane, |p| *p.get_ref()),
            thickness: r.thickness.as_ref().map_or(d.thickness, |t| *t.get_ref()),
            gravity: r.gravity,
            omega: r.omega.as_ref().map(|w| *w.get_ref()),
            centrifugal_factor: None,
            units: r.units,
            written_2d: [
                ("plane", r.plane.map(|p| p.span().start)),
                ("thickness", r.thickness.map(|t| t.span().start)),
                ("omega", r.omega.map(|w| w.span().start)),
            ],
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawContact {
    pub on: Option<String>,
    pub slave: Option<String>,
    pub master: Option<String>,
    pub normals: Option<NormalKind>,
    pub max_gap: Option<f64>,
    pub friction: Option<f64>,
    pub tresca: Option<f64>,
    pub discretization: Option<String>,
    pub interference: Option<bool>,
}

impl RawContact {
    /// The curve names given, with the key that gave each.
    pub fn names(&self) -> impl Iterator<Item = (&'static str, &str)> + '_ {
        [
            ("on", &self.on),
            ("slave", &self.slave),
            ("master", &self.master),
        ]
        .into_iter()
        .filter_map(|(k, n)| n.as_deref().map(|n| (k, n)))
    }
}

/// The whole problem file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFile {
    pub mesh: MeshSection,
    #[serde(default)]
    pub model: ModelSection,
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    #[serde(default)]
    pub dirichlet: Vec<RawDirichlet>,
    #[serde(default)]
    pub traction: Vec<RawTraction>,
    #[serde(default)]
    pub slip: Vec<Slip>,
    #[serde(default)]
    pub force: Vec<Force>,
    #[serde(default)]
    pub contact: Vec<RawContact>,
    #[serde(default)]
    pub solver: SolverSection,
    #[serde(default)]
    pub output: OutputSection,
    #[serde(default)]
    pub steps: Vec<LoadStep>,
}
