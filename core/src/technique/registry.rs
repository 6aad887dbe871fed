//! The registry: every technique ShadowLab has, with its role, its default comparison target, its shaders and
//! what it changes on a software adapter. The app's selectors, its comparison targets, the CLI's
//! `--technique`/`--indirect`/`--against*` and the test harness read these lists; no file outside a technique's
//! folder and this one names a technique's module (`core/tests/shaders.rs` holds the rule).

use super::{
    fuzzy, insm, ism, lightcluster, pathtraced, raytraced, reference, restir, unshadowed, val, vpl_gather, Technique,
};
use crate::gpu::GpuContext;
use crate::services::layouts::SharedLayouts;
use crate::shaders::WgslModule;
use crate::vpl::VplSource;

/// The per-light shadow-map reference: the default comparison target, and the oracle of the test harness.
pub const REFERENCE: &str = "reference";

/// What a technique is for in a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// One shadow map per light (per VPL): what the papers measure their approximations against.
    Reference,
    /// Exact visibility (ray traced, path traced): the truth a reference itself is checked against.
    GroundTruth,
    /// A faster approximation of a reference: the papers' techniques.
    Approximation,
    /// No visibility at all: a preview and a lower bound on time, never a target.
    Preview,
}

impl Role {
    /// Whether a technique of this role is offered as a comparison target.
    pub fn is_target(self) -> bool {
        matches!(self, Role::Reference | Role::GroundTruth)
    }

    pub fn name(self) -> &'static str {
        match self {
            Role::Reference => "reference",
            Role::GroundTruth => "ground truth",
            Role::Approximation => "approximation",
            Role::Preview => "preview",
        }
    }
}

/// A registered technique: its key, what it is for, and how to create it on a device.
pub struct TechniqueEntry {
    pub key: &'static str,
    pub label: &'static str,
    pub role: Role,
    /// The key (in the same registry) of the technique this one is compared with by default: the per-light
    /// reference for approximations, the ground truth for a reference, itself for a ground truth.
    pub target: &'static str,
    /// Tolerances of the test harness (`core/tests/harness.rs`) on its small scenes: mean absolute error of the
    /// display-referred image (0..1) and the largest share of pixels more than 0.1 off, against `target`; a
    /// ground truth (its own target) is held against the registry's other ground truth where one exists (the
    /// path tracer against `vpl-raytraced`) and is otherwise not checked (zero tolerances, unused).
    pub tolerance: Tolerance,
    pub create: fn(&GpuContext, &SharedLayouts) -> Box<dyn Technique>,
    /// The VPL source an indirect technique's paper uses, taken when the user chose none (`--vpl-source auto`).
    pub vpl_source: Option<VplSource>,
    /// Parameter values (as the parameter's text) a software adapter starts with, so a first frame on lavapipe
    /// or llvmpipe takes seconds, not minutes; the user can raise them.
    pub software_defaults: &'static [(&'static str, &'static str)],
    /// The technique's own composed WGSL modules (the shared ones are in [`crate::shaders::MODULES`]).
    pub shaders: &'static [WgslModule],
}

/// How close a technique must come to its target in the test harness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub mean_abs: f32,
    pub bad_pixel_share: f32,
}

const fn tolerance(mean_abs: f32, bad_pixel_share: f32) -> Tolerance {
    Tolerance { mean_abs, bad_pixel_share }
}

/// Every direct-light technique. The app's selector and the CLI's `--technique` read this list.
pub const REGISTRY: &[TechniqueEntry] = &[
    TechniqueEntry {
        key: REFERENCE,
        label: "Reference (cube shadow map per light)",
        role: Role::Reference,
        target: "raytraced",
        tolerance: tolerance(0.008, 0.05),
        create: |gpu, layouts| Box::new(reference::Reference::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[("shadow_res", "256")],
        shaders: &[],
    },
    TechniqueEntry {
        key: "unshadowed",
        label: "Unshadowed (no shadows, preview)",
        role: Role::Preview,
        target: REFERENCE,
        tolerance: tolerance(1.0, 1.0),
        create: |gpu, layouts| Box::new(unshadowed::Unshadowed::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[],
        shaders: unshadowed::SHADERS,
    },
    TechniqueEntry {
        key: "lightcluster",
        label: "LightCluster (clustered cube maps, PCF/PCSS)",
        role: Role::Approximation,
        target: REFERENCE,
        tolerance: tolerance(0.04, 0.14),
        create: |gpu, layouts| Box::new(lightcluster::LightCluster::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[("shadow_res", "256")],
        shaders: lightcluster::SHADERS,
    },
    TechniqueEntry {
        key: "insm",
        label: "INSM (intermediate shadow maps)",
        role: Role::Approximation,
        target: REFERENCE,
        tolerance: tolerance(0.015, 0.08),
        create: |gpu, layouts| Box::new(insm::Insm::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[],
        shaders: insm::SHADERS,
    },
    TechniqueEntry {
        key: "ism",
        label: "ISM (imperfect shadow maps, Ritschel 2008)",
        role: Role::Approximation,
        target: REFERENCE,
        // Measured (harness, 12,000 points per 128² map): worst on plate-shadow, mean abs 0.0341 with 16.8 % of
        // the pixels off (its 1 m² plate over a 400 m² ground gets about 30 points per map); unshadowed is
        // 0.054 / 19.0 % there.
        tolerance: tolerance(0.04, 0.18),
        create: |gpu, layouts| Box::new(ism::Ism::new(gpu, layouts)),
        vpl_source: None,
        // The paper's setup is already cheap on a software adapter: no triangle is drawn, and 1,024 lights splat
        // 12 M points (scripts/measure-ism's frames take seconds on lavapipe).
        software_defaults: &[],
        shaders: ism::SHADERS,
    },
    TechniqueEntry {
        key: "restir",
        label: "ReSTIR (spatiotemporal reservoir resampling, Bitterli 2020)",
        role: Role::Approximation,
        target: "raytraced",
        tolerance: tolerance(0.03, 0.1),
        create: |gpu, layouts| Box::new(restir::Restir::new(gpu, layouts)),
        vpl_source: None,
        // Eight averaged ReSTIR frames; a software adapter renders at half the window's size (~250 lines), where
        // the paper's 30 pixels (of 1080 lines) would reach across a third of the view.
        software_defaults: &[("frames", "8"), ("radius", "10")],
        shaders: restir::SHADERS,
    },
    TechniqueEntry {
        key: "raytraced",
        label: "Ray traced (ground truth)",
        role: Role::GroundTruth,
        target: "raytraced",
        tolerance: tolerance(0.0, 0.0),
        create: |gpu, layouts| Box::new(raytraced::Raytraced::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[],
        shaders: raytraced::SHADERS,
    },
];

/// The per-VPL reference of the indirect techniques: one shadow map per VPL.
pub const INDIRECT_REFERENCE: &str = "vpl-shadowmaps";

/// Every indirect technique: each adds the frame's indirect light into
/// [`FrameContext::indirect_buffer`](super::FrameContext::indirect_buffer). The app's second selector and the
/// CLI's `--indirect` read this list.
pub const INDIRECT_REGISTRY: &[TechniqueEntry] = &[
    TechniqueEntry {
        key: INDIRECT_REFERENCE,
        label: "VPLs, a shadow map each (instant radiosity)",
        role: Role::Reference,
        target: "vpl-raytraced",
        tolerance: tolerance(0.025, 0.02),
        create: |gpu, layouts| Box::new(vpl_gather::VplGather::new(gpu, layouts, vpl_gather::Visibility::ShadowMaps)),
        vpl_source: None,
        software_defaults: &[],
        shaders: &[],
    },
    TechniqueEntry {
        key: "vpl-raytraced",
        label: "VPLs, ray-traced visibility (ground truth)",
        role: Role::GroundTruth,
        target: "vpl-raytraced",
        tolerance: tolerance(0.0, 0.0),
        create: |gpu, layouts| Box::new(vpl_gather::VplGather::new(gpu, layouts, vpl_gather::Visibility::RayTraced)),
        vpl_source: None,
        software_defaults: &[],
        shaders: &[],
    },
    TechniqueEntry {
        key: "vpl-unshadowed",
        label: "VPLs, no visibility",
        role: Role::Preview,
        target: INDIRECT_REFERENCE,
        tolerance: tolerance(1.0, 1.0),
        create: |gpu, layouts| Box::new(vpl_gather::VplGather::new(gpu, layouts, vpl_gather::Visibility::None)),
        vpl_source: None,
        software_defaults: &[],
        shaders: &[],
    },
    TechniqueEntry {
        key: "val",
        label: "Virtual area lights (Dong 2009)",
        role: Role::Approximation,
        target: INDIRECT_REFERENCE,
        tolerance: tolerance(0.018, 0.05),
        create: |gpu, layouts| Box::new(val::VirtualAreaLights::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[],
        shaders: val::SHADERS,
    },
    TechniqueEntry {
        key: "vpl-ism",
        label: "VPLs, an imperfect shadow map each (Ritschel 2008)",
        role: Role::Approximation,
        target: INDIRECT_REFERENCE,
        // Measured (harness, 256 VPLs): worst on ceiling, mean abs 0.0361 with 10.2 % of the pixels off (points of
        // the ceiling behind the plate leak through its gaps); vpl-unshadowed is 0.059 / 17.7 % there. It was
        // 0.0307 / 8.7 % against per-VPL maps that drew the scene's long edges straight, which were 0.0176 off
        // the ray tracer there against 0.0057 now: ISM had agreed with the reference's leaks.
        tolerance: tolerance(0.042, 0.12),
        create: |gpu, layouts| Box::new(ism::VplIsm::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[],
        shaders: &[],
    },
    TechniqueEntry {
        key: "fuzzy",
        label: "Fuzzy clustering of shading points and VPLs (Colom 2022)",
        role: Role::Approximation,
        target: "vpl-raytraced",
        tolerance: tolerance(0.03, 0.07),
        create: |gpu, layouts| Box::new(fuzzy::FuzzyClustering::new(gpu, layouts)),
        vpl_source: Some(VplSource::Traced),
        software_defaults: &[],
        shaders: fuzzy::SHADERS,
    },
    TechniqueEntry {
        key: "pathtraced",
        label: "Path traced one bounce (truth)",
        role: Role::GroundTruth,
        target: "pathtraced",
        tolerance: tolerance(0.05, 0.19),
        create: |gpu, layouts| Box::new(pathtraced::PathTraced::new(gpu, layouts)),
        vpl_source: None,
        software_defaults: &[],
        shaders: pathtraced::SHADERS,
    },
];

/// The entry of the direct technique `key`.
pub fn entry(key: &str) -> Option<&'static TechniqueEntry> {
    REGISTRY.iter().find(|e| e.key == key)
}

/// The entry of the indirect technique `key`.
pub fn indirect_entry(key: &str) -> Option<&'static TechniqueEntry> {
    INDIRECT_REGISTRY.iter().find(|e| e.key == key)
}

/// The direct techniques a comparison can be made against (references and ground truths), in registry order.
pub fn targets() -> impl Iterator<Item = &'static TechniqueEntry> {
    REGISTRY.iter().filter(|e| e.role.is_target())
}

/// The indirect techniques a comparison can be made against.
pub fn indirect_targets() -> impl Iterator<Item = &'static TechniqueEntry> {
    INDIRECT_REGISTRY.iter().filter(|e| e.role.is_target())
}

/// The direct technique the app previews with while a light or the camera moves (the one of role `Preview`).
pub fn preview() -> &'static TechniqueEntry {
    REGISTRY.iter().find(|e| e.role == Role::Preview).expect("the registry has a preview technique")
}

/// Create an indirect technique by key.
pub fn create_indirect(key: &str, gpu: &GpuContext, layouts: &SharedLayouts) -> Option<Box<dyn Technique>> {
    indirect_entry(key).map(|e| (e.create)(gpu, layouts))
}

/// The comparison target an indirect technique declares (`val`: `vpl-shadowmaps`), None for a ground truth
/// (its own target) or an unknown key. Comparing the indirect light alone with the same technique differs by
/// nothing, so the CLI, the trade-off and the app compare it with this one unless told otherwise.
pub fn own_indirect_target(key: &str) -> Option<&'static str> {
    indirect_entry(key).map(|e| e.target).filter(|t| *t != key)
}

/// The VPL source the indirect technique `key`'s paper uses (Colom 2022 traces particles), None when it has
/// no preference or is unknown.
pub fn preferred_vpl_source(key: &str) -> Option<VplSource> {
    indirect_entry(key).and_then(|e| e.vpl_source)
}

/// The keys of all indirect techniques, for error messages.
pub fn indirect_keys() -> String {
    INDIRECT_REGISTRY.iter().map(|e| e.key).collect::<Vec<_>>().join(", ")
}

/// Create a technique by key.
pub fn create(key: &str, gpu: &GpuContext, layouts: &SharedLayouts) -> Option<Box<dyn Technique>> {
    entry(key).map(|e| (e.create)(gpu, layouts))
}

/// The keys of all techniques, for error messages.
pub fn keys() -> String {
    REGISTRY.iter().map(|e| e.key).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_indirect_technique_names_its_own_target_and_a_ground_truth_none() {
        assert_eq!(own_indirect_target("val"), Some(INDIRECT_REFERENCE));
        assert_eq!(own_indirect_target("fuzzy"), Some("vpl-raytraced"));
        assert_eq!(own_indirect_target("pathtraced"), None, "a ground truth is its own target");
        assert_eq!(own_indirect_target("nope"), None);
        for e in INDIRECT_REGISTRY {
            assert!(own_indirect_target(e.key).is_none_or(|t| indirect_entry(t).is_some()), "{}", e.key);
        }
    }

    #[test]
    fn every_target_is_registered_and_is_a_target() {
        for (list, find) in
            [(REGISTRY, entry as fn(&str) -> Option<&'static TechniqueEntry>), (INDIRECT_REGISTRY, indirect_entry)]
        {
            for e in list {
                let target =
                    find(e.target).unwrap_or_else(|| panic!("{}: target {} is not registered", e.key, e.target));
                assert!(target.role.is_target(), "{}: target {} is a {}", e.key, e.target, target.role.name());
                if e.role == Role::GroundTruth {
                    assert_eq!(e.target, e.key, "a ground truth is its own target");
                }
            }
            assert_eq!(list.iter().filter(|e| e.role == Role::Reference).count(), 1, "one reference per registry");
        }
        assert_eq!(entry(REFERENCE).map(|e| e.role), Some(Role::Reference));
        assert_eq!(preview().role, Role::Preview);
        assert!(targets().all(|e| e.role.is_target()) && targets().any(|e| e.key == REFERENCE));
        assert_eq!(indirect_entry(INDIRECT_REFERENCE).map(|e| e.role), Some(Role::Reference));
    }
}
