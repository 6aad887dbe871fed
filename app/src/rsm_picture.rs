//! A light's reflective shadow map ([`RsmImage`]) as a picture: a cube unfolded as a cross (the layout the
//! shadow-map inspector unfolds cube maps in), a spot's face or a sun's square; per texel its reflected flux,
//! its normal or its distance; the readout of a texel. Shared by the app's RSM view
//! ([`crate::gui::rsm_view`]) and `shadowlab render --rsm-out`.

use std::collections::BTreeMap;

use glam::Vec3;
use shadowlab_core::vpl::rsm::{RsmImage, RsmLayout};

/// Where each face of a cube goes in the cross, in tiles: +y on top, −x +z +x −z across, −y below.
pub const CROSS: [(u32, u32); 6] = [(2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (3, 1)];
/// The faces' names in the order cube maps store them.
pub const FACES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];
/// Outside the cross.
const OUTSIDE: [u8; 4] = [20, 24, 40, 255];
/// A texel that sees nothing (its ray leaves the scene or the light's range): a checkerboard of 4-texel
/// squares, so it is not taken for a dark surface.
pub const EMPTY: [[u8; 4]; 2] = [[62, 62, 66, 255], [40, 40, 44, 255]];
/// A texel a VPL was drawn from, in a file.
pub const MARK: [u8; 4] = [255, 60, 200, 255];

/// What a texel's colour shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RsmShow {
    /// `Phi_p`, tone-mapped against the brightest texels.
    Flux,
    /// `n_p` as RGB (`0.5 n + 0.5`).
    Normal,
    /// Distance from the light, near white, far dark.
    Distance,
}

/// The picture's size in texels: a cross of 4 x 3 faces for a cube, else one face.
pub fn picture_size(image: &RsmImage) -> [u32; 2] {
    let r = image.resolution;
    match image.layout {
        RsmLayout::Cube { .. } => [4 * r, 3 * r],
        _ => [r, r],
    }
}

/// The picture pixel of texel `(x, y)` of face `face`.
pub fn pixel_of(image: &RsmImage, face: u32, x: u32, y: u32) -> (u32, u32) {
    let r = image.resolution;
    match image.layout {
        RsmLayout::Cube { .. } => {
            let (cx, cy) = CROSS[face as usize % 6];
            (cx * r + x, cy * r + y)
        }
        _ => (x, y),
    }
}

/// The texel (face, x, y) at picture pixel `(px, py)`; None outside the cross.
pub fn texel_at(image: &RsmImage, px: u32, py: u32) -> Option<(u32, u32, u32)> {
    let r = image.resolution;
    match image.layout {
        RsmLayout::Cube { .. } => {
            let face = CROSS.iter().position(|&(cx, cy)| (cx, cy) == (px / r, py / r))?;
            Some((face as u32, px % r, py % r))
        }
        _ => (px < r && py < r).then_some((0, px, py)),
    }
}

/// The map as colours: flux (tone-mapped so the 99th percentile of the brightest channel is white), normals or
/// distance; texels that see nothing a grey checkerboard ([`EMPTY`]), outside the cross dark blue.
pub fn picture(image: &RsmImage, show: RsmShow) -> image::RgbaImage {
    let [w, h] = picture_size(image);
    let texels = image.texels.iter().flatten();
    let mut brightest: Vec<f32> = texels.clone().map(|t| t.flux.max_element()).collect();
    brightest.sort_by(f32::total_cmp);
    let white = brightest.get(brightest.len() * 99 / 100).copied().unwrap_or(1.0).max(1e-12);
    let (near, far) = texels.fold((f32::INFINITY, 0.0f32), |(lo, hi), t| (lo.min(t.distance), hi.max(t.distance)));
    let span = (far - near).max(1e-6);
    let byte = |v: f32| (255.0 * v.clamp(0.0, 1.0)) as u8;
    let pixels = (0..h)
        .flat_map(|py| (0..w).map(move |px| (px, py)))
        .flat_map(|(px, py)| {
            let Some((face, x, y)) = texel_at(image, px, py) else { return OUTSIDE };
            let Some(t) = image.texel(face, x, y) else { return EMPTY[((x / 4 + y / 4) % 2) as usize] };
            let c = match show {
                RsmShow::Flux => (t.flux / white).clamp(Vec3::ZERO, Vec3::ONE).powf(1.0 / 2.2),
                RsmShow::Normal => t.normal * 0.5 + 0.5,
                RsmShow::Distance => Vec3::splat(1.0 - 0.85 * (t.distance - near) / span),
            };
            [byte(c.x), byte(c.y), byte(c.z), 255]
        })
        .collect();
    image::RgbaImage::from_raw(w, h, pixels).expect("w x h pixels")
}

/// Mark the texels VPLs were drawn from in `picture` (for a file; the app rings them instead): each with a
/// 3 x 3 block around it, so it shows at any resolution.
pub fn mark_drawn(picture: &mut image::RgbaImage, image: &RsmImage, drawn: &BTreeMap<(u32, u32, u32), u32>) {
    let (w, h) = picture.dimensions();
    for &(face, x, y) in drawn.keys() {
        let (px, py) = pixel_of(image, face, x, y);
        for (mx, my) in
            (px.saturating_sub(1)..=px + 1).flat_map(|mx| (py.saturating_sub(1)..=py + 1).map(move |my| (mx, my)))
        {
            if mx < w && my < h {
                picture.put_pixel(mx, my, image::Rgba(MARK));
            }
        }
    }
}

/// The readout of picture pixel `(px, py)`: the texel, what it sees, its flux and the VPLs drawn from it.
pub fn readout(image: &RsmImage, drawn: &BTreeMap<(u32, u32, u32), u32>, px: u32, py: u32) -> Option<String> {
    let (face, x, y) = texel_at(image, px, py)?;
    let at = match image.layout {
        RsmLayout::Cube { .. } => format!("face {} texel ({x}, {y})", FACES[face as usize]),
        _ => format!("texel ({x}, {y})"),
    };
    let Some(t) = image.texel(face, x, y) else { return Some(format!("{at} · sees nothing")) };
    let v = |v: Vec3| format!("({:.2}, {:.2}, {:.2})", v.x, v.y, v.z);
    let vpls = match drawn.get(&(face, x, y)) {
        Some(n) => format!(" · {n} VPL{} drawn here", if *n == 1 { "" } else { "s" }),
        None => String::new(),
    };
    Some(format!(
        "{at} · position {} · normal {} · distance {:.3} · flux ({:.3e}, {:.3e}, {:.3e}){vpls}",
        v(t.position),
        v(t.normal),
        t.distance,
        t.flux.x,
        t.flux.y,
        t.flux.z
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab_core::vpl::rsm::RsmTexel;

    /// A cube of 2² texels a face where only face +y (2) sees something: texel (x, y) at distance 1 + x + 2y,
    /// flux growing with it, normal -y.
    fn cube() -> RsmImage {
        let r = 2;
        let texels = (0..6u32)
            .flat_map(|f| (0..r).flat_map(move |y| (0..r).map(move |x| (f, x, y))))
            .map(|(f, x, y)| {
                (f == 2).then(|| RsmTexel {
                    position: Vec3::new(x as f32, 3.0, y as f32),
                    normal: -Vec3::Y,
                    flux: Vec3::splat((1 + x + 2 * y) as f32),
                    distance: (1 + x + 2 * y) as f32,
                })
            })
            .collect();
        RsmImage { layout: RsmLayout::Cube { eye: Vec3::ZERO }, resolution: r, faces: 6, texels }
    }

    #[test]
    fn a_cubes_rsm_unfolds_into_the_inspectors_cross_and_reads_back_each_texel() {
        let image = cube();
        assert_eq!(picture_size(&image), [8, 6]);
        // Every texel of every face round-trips through the cross; the corners are outside it.
        for face in 0..6 {
            for (x, y) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (px, py) = pixel_of(&image, face, x, y);
                assert_eq!(texel_at(&image, px, py), Some((face, x, y)));
            }
        }
        assert_eq!(texel_at(&image, 0, 0), None);
        let picture = picture(&image, RsmShow::Flux);
        assert_eq!(picture.dimensions(), (8, 6));
        // +y sits on top in the second column: its brightest texel (1, 1) is white, its dimmest darker.
        let at = |p: &image::RgbaImage, x: u32, y: u32| p.get_pixel(x, y).0;
        assert_eq!(at(&picture, 3, 1), [255; 4]);
        assert!(at(&picture, 2, 0)[0] < 200 && at(&picture, 2, 0)[0] > 0);
        assert_eq!((at(&picture, 0, 2), at(&picture, 1, 3)), (EMPTY[0], EMPTY[0]), "-x sees nothing");
        assert_eq!(at(&picture, 0, 0), OUTSIDE, "outside the cross");
        // Normals -y: (0.5, 0, 0.5) in RGB; distance: the nearest white-ish, the farthest darker.
        let normals = super::picture(&image, RsmShow::Normal);
        assert_eq!((at(&normals, 2, 0)[1], at(&normals, 2, 0)[0]), (0, 127));
        let distance = super::picture(&image, RsmShow::Distance);
        assert!(at(&distance, 2, 0)[0] > at(&distance, 3, 1)[0]);
        let mut drawn = BTreeMap::new();
        drawn.insert((2, 1, 0), 3);
        let text = readout(&image, &drawn, 3, 0).unwrap();
        assert!(text.starts_with("face +y texel (1, 0)") && text.contains("distance 2.000"), "{text}");
        assert!(text.ends_with("3 VPLs drawn here"), "{text}");
        assert!(readout(&image, &drawn, 2, 2).unwrap().ends_with("sees nothing"));
        assert_eq!(readout(&image, &drawn, 0, 0), None);
        let mut marked = picture.clone();
        mark_drawn(&mut marked, &image, &drawn);
        assert_eq!(at(&marked, 3, 0), MARK, "+y's texel (1, 0) is marked");
        // A 3 x 3 block around it, cut by the picture's top edge.
        assert_eq!(marked.pixels().filter(|p| p.0 == MARK).count(), 6);
        assert_eq!((at(&marked, 4, 1), at(&marked, 1, 0)), (MARK, OUTSIDE));
    }
}
