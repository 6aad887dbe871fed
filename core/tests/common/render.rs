//! The render helpers every GPU test uses: a direct technique, or an indirect one over a direct one, by its
//! registry key with parameters, on a scene, camera and lights at a size ([`Shot`]); one frame on a renderer a
//! test keeps ([`frame`]); and the display-referred comparison of two images ([`display_difference`]) the test
//! harness measures its tolerances with.

use glam::Vec3;
use shadowlab_core::compare::{luminance, tonemap_for_flip, Image};
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::{Camera, PointLight, Scene};
use shadowlab_core::technique::{ParamValue, Technique};
use shadowlab_core::vpl::{VplSet, VplSettings};
use shadowlab_core::{FrameReport, GpuContext, RenderSettings, Renderer, ToneMap};

/// Technique parameters: key and value.
pub type Params<'a> = &'a [(&'a str, ParamValue)];

/// Render settings of the image tests: `width` x `height`, a linear tone map (radiance 1 is white), the rest as
/// the renderer's defaults.
pub fn linear_settings(width: u32, height: u32) -> RenderSettings {
    RenderSettings { width, height, tonemap: ToneMap::Linear, ..Default::default() }
}

/// A new renderer of `scene` on a new GPU context.
pub fn renderer(scene: &Scene, settings: RenderSettings) -> Renderer {
    Renderer::new(&super::gpu(), scene, settings).unwrap()
}

/// Settings of the indirect-light tests: `width` x `height`, linear, no ambient light, a black background, the
/// indirect component alone, these VPLs.
pub fn indirect_settings(width: u32, height: u32, vpl: VplSettings) -> RenderSettings {
    RenderSettings {
        ambient: Vec3::ZERO,
        background: Vec3::ZERO,
        component: Component::Indirect,
        vpl,
        ..linear_settings(width, height)
    }
}

/// Set every one of `params` on `technique`; a refused value fails the test with the key and the reason.
pub fn set_params(technique: &mut dyn Technique, params: Params) {
    for (k, v) in params {
        technique.set_param(k, v).unwrap_or_else(|e| panic!("{}: {k} = {v}: {e}", technique.key()));
    }
}

/// The direct technique `key` on `renderer`'s device, with `params` set.
pub fn create(renderer: &Renderer, key: &str, params: Params) -> Box<dyn Technique> {
    let mut t = renderer.create_technique(key).unwrap_or_else(|| panic!("no direct technique '{key}'"));
    set_params(t.as_mut(), params);
    t
}

/// The indirect technique `key` on `renderer`'s device, with `params` set.
pub fn create_indirect(renderer: &Renderer, key: &str, params: Params) -> Box<dyn Technique> {
    let mut t = renderer.create_indirect_technique(key).unwrap_or_else(|| panic!("no indirect technique '{key}'"));
    set_params(t.as_mut(), params);
    t
}

/// One whole frame of `technique` (and the renderer's indirect technique, if any): the HDR image of the
/// settings' component and the report.
pub fn frame(
    renderer: &mut Renderer,
    technique: &mut dyn Technique,
    camera: &Camera,
    lights: &[PointLight],
) -> (Vec<[f32; 4]>, FrameReport) {
    let report = renderer.render_frame(technique, camera, lights, &mut |_, _| {}).unwrap();
    (renderer.read_hdr().unwrap(), report)
}

/// One whole frame of a new direct technique `key` with `params` on `renderer`.
pub fn frame_of(
    renderer: &mut Renderer,
    key: &str,
    params: Params,
    camera: &Camera,
    lights: &[PointLight],
) -> (Vec<[f32; 4]>, FrameReport) {
    let mut t = create(renderer, key, params);
    frame(renderer, t.as_mut(), camera, lights)
}

/// A frame on a new renderer: a direct technique, optionally an indirect one (with fixed VPLs), on a GPU of its
/// own unless [`Shot::on`] gives one.
pub struct Shot<'a> {
    scene: &'a Scene,
    camera: Camera,
    lights: &'a [PointLight],
    settings: RenderSettings,
    direct: &'a str,
    direct_params: Vec<(&'a str, ParamValue)>,
    indirect: Option<(&'a str, Vec<(&'a str, ParamValue)>)>,
    fixed_vpls: Option<VplSet>,
    gpu: Option<GpuContext>,
}

/// What [`Shot::render_keeping`] returns: the renderer (to read positions, masks, components) with the image
/// and the report.
pub struct Rendered {
    pub renderer: Renderer,
    pub hdr: Vec<[f32; 4]>,
    pub report: FrameReport,
}

impl<'a> Shot<'a> {
    /// The direct technique `key` on `scene` from its camera.
    pub fn direct(scene: &'a Scene, lights: &'a [PointLight], settings: RenderSettings, key: &'a str) -> Shot<'a> {
        Shot {
            scene,
            camera: scene.camera,
            lights,
            settings,
            direct: key,
            direct_params: Vec::new(),
            indirect: None,
            fixed_vpls: None,
            gpu: None,
        }
    }

    /// The indirect technique `key` over the unshadowed direct light ([`Shot::with_direct`] picks another);
    /// `settings.component` = `Indirect` shows the indirect part alone.
    pub fn indirect(scene: &'a Scene, lights: &'a [PointLight], settings: RenderSettings, key: &'a str) -> Shot<'a> {
        Shot { indirect: Some((key, Vec::new())), ..Shot::direct(scene, lights, settings, "unshadowed") }
    }

    /// Parameters of the technique under test: the indirect one when there is one, else the direct one.
    pub fn params(mut self, params: Params<'a>) -> Shot<'a> {
        match &mut self.indirect {
            Some((_, p)) => p.extend(params.iter().cloned()),
            None => self.direct_params.extend(params.iter().cloned()),
        }
        self
    }

    /// The direct technique under an indirect one, with its parameters.
    pub fn with_direct(mut self, key: &'a str, params: Params<'a>) -> Shot<'a> {
        self.direct = key;
        self.direct_params = params.to_vec();
        self
    }

    /// Render from `camera` instead of the scene's.
    pub fn camera(mut self, camera: &Camera) -> Shot<'a> {
        self.camera = *camera;
        self
    }

    /// Use these VPLs instead of generating them ([`Renderer::set_fixed_vpls`]); None generates them.
    pub fn fixed_vpls(mut self, set: Option<VplSet>) -> Shot<'a> {
        self.fixed_vpls = set;
        self
    }

    /// Render on this GPU context (another backend) instead of a new one.
    pub fn on(mut self, gpu: GpuContext) -> Shot<'a> {
        self.gpu = Some(gpu);
        self
    }

    /// Render the frame: the HDR image of the settings' component and the report.
    pub fn render(self) -> (Vec<[f32; 4]>, FrameReport) {
        let r = self.render_keeping();
        (r.hdr, r.report)
    }

    /// Render the frame and keep the renderer.
    pub fn render_keeping(self) -> Rendered {
        let mut renderer = match &self.gpu {
            Some(gpu) => Renderer::new(gpu, self.scene, self.settings).unwrap(),
            None => renderer(self.scene, self.settings),
        };
        let mut direct = create(&renderer, self.direct, &self.direct_params);
        if let Some((key, params)) = &self.indirect {
            let t = create_indirect(&renderer, key, params);
            renderer.set_indirect(Some(t)).unwrap();
        }
        if self.fixed_vpls.is_some() {
            renderer.set_fixed_vpls(self.fixed_vpls);
        }
        let (hdr, report) = frame(&mut renderer, direct.as_mut(), &self.camera, self.lights);
        Rendered { renderer, hdr, report }
    }
}

/// A pixel is "off" when one of its display-referred channels (0..1) differs by more than this.
pub const BAD_PIXEL: f32 = 0.1;

/// Two images compared as a viewer sees them ([`display`]).
#[derive(Clone, Debug)]
pub struct Difference {
    /// Compared pixels (the mask's, or all).
    pub pixels: usize,
    /// Mean absolute difference of the display-referred channels (0..1) over the compared pixels.
    pub mean_abs: f32,
    /// Share of the compared pixels with a channel more than [`BAD_PIXEL`] off.
    pub bad_share: f32,
    /// Largest channel difference.
    pub worst: f32,
    /// Per pixel: compared and more than [`BAD_PIXEL`] off.
    pub bad: Vec<bool>,
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "mean abs {:.4}, {:.2} % of {} pixels more than {BAD_PIXEL} off, worst {:.3}",
            self.mean_abs,
            self.bad_share * 100.0,
            self.pixels,
            self.worst
        )
    }
}

/// The display-referred image: `radiance · exposure` through the renderer's ACES tone mapping and sRGB encoding,
/// in 8 bits ([`tonemap_for_flip`]), as 0..1 per channel.
pub fn display(hdr: &[[f32; 4]], width: u32, height: u32, exposure: f32) -> Vec<[f32; 3]> {
    let image = Image::new(width, height, hdr.to_vec()).unwrap();
    tonemap_for_flip(&image, exposure).pixels().map(|p| p.0.map(|c| c as f32 / 255.0)).collect()
}

/// `actual` against `expected`, display-referred at `exposure`, over the pixels where `mask` is true (all when
/// None).
pub fn display_difference(
    actual: &[[f32; 4]],
    expected: &[[f32; 4]],
    width: u32,
    height: u32,
    exposure: f32,
    mask: Option<&[bool]>,
) -> Difference {
    let (a, e) = (display(actual, width, height, exposure), display(expected, width, height, exposure));
    let (mut pixels, mut sum, mut worst, mut over) = (0usize, 0f64, 0f32, 0usize);
    let mut bad = vec![false; a.len()];
    for i in 0..a.len() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        pixels += 1;
        let d = (0..3).map(|c| (a[i][c] - e[i][c]).abs());
        let (s, m) = d.fold((0f32, 0f32), |(s, m), x| (s + x, m.max(x)));
        sum += s as f64;
        worst = worst.max(m);
        if m > BAD_PIXEL {
            over += 1;
            bad[i] = true;
        }
    }
    let n = pixels.max(1);
    Difference { pixels, mean_abs: (sum / (3 * n) as f64) as f32, bad_share: over as f32 / n as f32, worst, bad }
}

/// The exposure the renderer's auto-exposure would meter for `hdr`: middle grey (0.18) over the log-average
/// luminance of the pixels where `mask` is true (1 when there are none).
pub fn metered_exposure(hdr: &[[f32; 4]], mask: &[bool]) -> f32 {
    let (sum, n) = hdr
        .iter()
        .zip(mask)
        .filter(|(_, &g)| g)
        .fold((0f64, 0usize), |(s, n), (p, _)| (s + (1e-4 + luminance(*p).max(0.0) as f64).ln(), n + 1));
    if n == 0 {
        1.0
    } else {
        (0.18 / (sum / n as f64).exp()) as f32
    }
}
