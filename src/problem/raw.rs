//! The problem file as serde reads it: the `[[contact]]`, `[[dirichlet]]`
//! and `[[traction]]` entries with their keys as loose options, exactly as
//! written. `validate` turns them into the typed entries of [`super`] once,
//! so that no consumer has to test which keys are present.

use super::{
    opt_pair, Force, LoadStep, Material, MeshSection, ModelSection, NormalKind, OutputSection, Slip,
};
use crate::qp::SolverSection;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDirichlet {
    pub on: String,
    #[serde(default, deserialize_with = "opt_pair")]
    pub u: Option<[f64; 2]>,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
}

impl RawDirichlet {
    /// Every prescribed value given, in the order u, ux, uy.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.u
            .iter()
            .flatten()
            .chain(&self.ux)
            .chain(&self.uy)
            .copied()
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTraction {
    pub on: String,
    #[serde(default, deserialize_with = "opt_pair")]
    pub p: Option<[f64; 2]>,
    pub pn: Option<f64>,
}

impl RawTraction {
    /// Every traction value given, in the order p, pn.
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.p.iter().flatten().chain(&self.pn).copied()
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
