//! The Explain steps of the VPL gathers: instant radiosity's VPLs, each VPL's visibility, and interleaved sampling
//! with the paper's blur and with the ratio estimator (Dong et al. 2009 section 6; each step sets the parameters
//! that show it).

use super::Visibility;
use crate::technique::ExplainStep;

/// The steps, the second one as `visibility` finds it.
pub(super) fn explain_steps(visibility: Visibility) -> Vec<ExplainStep> {
    let (visibility_text, shows_maps) = match visibility {
        Visibility::ShadowMaps => (
            "One paraboloid shadow map per VPL, facing its normal (see Shadow maps: the last batch's), the scene's \
             long edges cut first since a paraboloid draws edges straight; a pixel tests each VPL's map once. The \
             VALs' reference.",
            true,
        ),
        Visibility::RayTraced => (
            "A shadow ray from the pixel to every VPL through the scene's BVH: exact VPL visibility, the truth the \
             other VPL techniques are measured against, and the slowest.",
            false,
        ),
        Visibility::None => (
            "None: every VPL lights every pixel in front of it, as if nothing stood between them; the \
             denominator of indirect shadows.",
            false,
        ),
    };
    vec![
        ExplainStep {
            title: "1. Virtual point lights",
            text: "Where each light's light first lands (a texel of its reflective shadow map, or a particle's \
                   bounce) a VPL stands, reflecting the surface's share of the flux; it sends Phi/pi cos cos / \
                   max(d^2, d_clamp^2) to a pixel. Coloured by flux.",
            layers: &["vpls (flux)", "vpls (flux, every n-th)", "vpl normals", "vpl normals (every n-th)"],
            shows_shadow_maps: true,
            maps: crate::technique::RSM_MAPS,
            params: &[("interleave", "off")],
        },
        ExplainStep {
            title: "2. Each VPL's visibility",
            text: visibility_text,
            layers: &[],
            shows_shadow_maps: shows_maps,
            params: &[("interleave", "off")],
            ..Default::default()
        },
        ExplainStep {
            title: "3. Interleaved sampling (the paper's blur)",
            text: "Each pixel of an 8x8 block gathers every 64th VPL, times 64: 64 times fewer visibility tests. \
                   A geometry-aware blur over the block (same surface: the tangent plane, the normal) spreads every \
                   VPL over it again, averaging the light itself, so a near VPL's falloff and the normals' detail \
                   blur with it.",
            layers: &[],
            params: &[("interleave", "on"), ("ratio", "off"), ("block", "8")],
            ..Default::default()
        },
        ExplainStep {
            title: "4. The ratio estimator",
            text: "The blur averages visibility only: each pixel sums its unshadowed light from every VPL (no \
                   test, cheap) and multiplies it by the share its window saw unblocked. Without shadows this is \
                   the full gather exactly; 'Interleaving block' 4 or 2 blurs less for more tests.",
            layers: &[],
            params: &[("interleave", "on"), ("ratio", "on"), ("block", "8")],
            ..Default::default()
        },
    ]
}
