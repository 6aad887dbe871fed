//! The app driven through egui_kittest on the software adapter: snapshots of the main window, the light
//! inspector and the timings panel, and a whole edit session (select, move with the gizmo, undo, redo, save,
//! load in a fresh app).

use std::path::PathBuf;

use eframe::egui;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use shadowlab::gui::gizmo::{self, Projection};
use shadowlab::gui::layout::Pane;
use shadowlab::gui::{ShadowLabApp, StartState, Startup};
use shadowlab::sequence::Motion;

fn data_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/app").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SIZE: (f32, f32) = (900.0, 560.0);

/// Snapshots without the timings panel (its milliseconds change from run to run) and toasts.
fn snapshot(h: &mut Harness<'static, ShadowLabApp>, name: &str) {
    let timings = h.state().chrome.layout.rect(Pane::Timings).expect("the timings panel is laid out");
    h.mask(timings);
    h.mask(egui::Rect::from_min_max(egui::pos2(SIZE.0 - 420.0, SIZE.1 - 120.0), egui::pos2(SIZE.0, SIZE.1)));
    h.snapshot(name);
}

fn harness(startup: Startup) -> Harness<'static, ShadowLabApp> {
    harness_sized(startup, SIZE)
}

fn harness_sized(startup: Startup, size: (f32, f32)) -> Harness<'static, ShadowLabApp> {
    let mut h = Harness::builder()
        .with_size(egui::vec2(size.0, size.1))
        .wgpu_setup(shadowlab::gui::wgpu_setup())
        .with_max_steps(40)
        .build_eframe(move |cc| ShadowLabApp::new(cc, startup).expect("the app starts on the software adapter"));
    h.run_steps(3);
    h
}

/// A fresh app opened on a saved scene file, as a user reopening it would see it.
fn reopen(file: &std::path::Path, dir: &std::path::Path) -> Harness<'static, ShadowLabApp> {
    harness(Startup {
        path: Some(file.to_path_buf()),
        data_dir: Some(dir.to_path_buf()),
        synchronous: true,
        ..Default::default()
    })
}

/// The app as a class or a script starts it: its start options (`--app-*`), on built-in scene `builtin` if any.
fn started(name: &str, builtin: Option<&str>, start: StartState) -> Harness<'static, ShadowLabApp> {
    harness(Startup {
        data_dir: Some(data_dir(name)),
        synchronous: true,
        builtin: builtin.map(str::to_string),
        start,
        ..Default::default()
    })
}

fn start(name: &str, scene: &str) -> Harness<'static, ShadowLabApp> {
    let mut h = harness(Startup { data_dir: Some(data_dir(name)), synchronous: true, ..Default::default() });
    h.state_mut().load_builtin(scene);
    h.run_steps(3);
    h
}

fn press(h: &mut Harness<'static, ShadowLabApp>, pos: egui::Pos2, pressed: bool, modifiers: egui::Modifiers) {
    h.event(egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed, modifiers });
    h.step();
}

fn move_to(h: &mut Harness<'static, ShadowLabApp>, pos: egui::Pos2) {
    h.event(egui::Event::PointerMoved(pos));
    h.step();
}

fn projection(h: &Harness<'static, ShadowLabApp>) -> Projection {
    let app = h.state();
    Projection::new(&app.session.camera.camera(), app.views.last_viewport_rect.expect("the view was laid out"))
}

#[test]
fn main_window_on_a_builtin_scene() {
    let mut h = start("main", "cornell");
    assert_eq!(h.state().session.lights.len(), 32);
    h.get_by_label("Technique");
    // The lights' panel is a tab of the left column.
    h.get_by_label("Lights");
    let report = h.state().views.gpu.as_ref().unwrap().main.last_report.clone().expect("a complete frame");
    assert_eq!(report.counts.technique.shadow_maps, 32);
    snapshot(&mut h, "main_window_cornell");
}

#[test]
fn light_inspector_shows_the_selected_light() {
    let mut h = start("inspector", "cornell");
    h.state_mut().session.selected = Some(3);
    h.run_steps(2);
    h.get_by_label("Light 3");
    assert!(h.query_all_by_label("L_att").count() >= 1, "the L_att slider is shown");
    snapshot(&mut h, "light_inspector");
}

#[test]
fn the_inspector_turns_a_light_into_a_spot_light() {
    let mut h = start("inspector-spot", "cornell");
    h.state_mut().session.selected = Some(3);
    h.run_steps(2);
    assert!(h.state().session.lights[3].spot.is_none());
    h.get_by_label("spot light").click();
    h.run_steps(2);
    let spot = h.state().session.lights[3].spot.expect("the checkbox made a spot light");
    assert!((spot.outer_angle - 30f32.to_radians()).abs() < 1e-4 && spot.direction.y < -0.99, "{spot:?}");
    assert!(h.query_all_by_label_contains("cone half-angle").count() >= 1, "the cone slider is shown");
    // The spot's cone is drawn as an overlay layer.
    h.state_mut().chrome.layout.focus(Pane::Overlays);
    h.run_steps(1);
    assert!(h.query_all_by_label_contains("spot cones").count() >= 1, "no spot cone layer");
}

#[test]
fn timings_panel_lists_passes_and_counts() {
    let mut h = start("timings", "restaurant");
    h.run_steps(2);
    let report = h.state().views.gpu.as_ref().and_then(|g| g.main.last_report.clone()).expect("a complete frame");
    // Per pass in GPU timestamps; per step where `auto` chose the wall clock (a loaded machine can make it).
    let names: &[&str] = if report.timing.source == shadowlab_core::timing::TimingSource::GpuTimestamps {
        &["gbuffer", "shadow maps", "shading", "tonemap"]
    } else {
        &["gbuffer + ambient", "tonemap"]
    };
    for &pass in names {
        // In the table and in the plot's legend.
        assert!(h.query_all_by_label(pass).count() >= 1, "no '{pass}' in the timings panel");
    }
    h.get_by_label_contains("14 of 14 lights visible");
    h.get_by_label_contains("adapter:");
}

#[test]
fn edit_session_select_move_undo_redo_save_and_reload() {
    let dir = data_dir("session");
    let mut h = start("session", "cornell");
    // Select light 5 by clicking on it.
    let target = 5;
    let at = h.state().session.lights[target].position;
    let p = projection(&h);
    let pos = p.to_screen(at).unwrap();
    let picked = gizmo::pick_light(&p, &h.state().session.lights, pos, 12.0).unwrap();
    move_to(&mut h, pos);
    press(&mut h, pos, true, egui::Modifiers::NONE);
    press(&mut h, pos, false, egui::Modifiers::NONE);
    assert_eq!(h.state().session.selected, Some(picked), "a click on a light selects it");
    let start_pos = h.state().session.lights[picked].position;

    // Drag the X handle of the gizmo by 60 points, in small moves.
    let p = projection(&h);
    let center = p.to_screen(start_pos).unwrap();
    let handle_end = (0..=70)
        .map(|d| center + egui::vec2(d as f32, 0.0))
        .chain((0..=70).map(|d| center - egui::vec2(d as f32, 0.0)))
        .find(|&q| q.distance(center) > 30.0 && gizmo::hit_handle(&p, start_pos, q) == Some(gizmo::Handle::Axis(0)));
    let grab = handle_end.unwrap_or_else(|| {
        // The x axis may point elsewhere on screen; search around the center.
        (0..360)
            .step_by(5)
            .map(|a| center + egui::Vec2::angled((a as f32).to_radians()) * 45.0)
            .find(|&q| gizmo::hit_handle(&p, start_pos, q) == Some(gizmo::Handle::Axis(0)))
            .expect("the x handle is on screen")
    });
    move_to(&mut h, grab);
    press(&mut h, grab, true, egui::Modifiers::NONE);
    let dir_on_screen = (grab - center).normalized();
    for i in 1..=6 {
        move_to(&mut h, grab + dir_on_screen * (10.0 * i as f32));
    }
    press(&mut h, grab + dir_on_screen * 60.0, false, egui::Modifiers::NONE);
    let moved = h.state().session.lights[picked].position;
    assert!((moved.x - start_pos.x).abs() > 0.01, "the light moved along x: {start_pos} -> {moved}");
    assert!((moved.y - start_pos.y).abs() < 1e-5 && (moved.z - start_pos.z).abs() < 1e-5, "only along x");

    // Undo and redo with the keyboard.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().session.lights[picked].position, start_pos, "Ctrl+Z restores the position");
    h.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(h.state().session.lights[picked].position, moved, "Ctrl+Shift+Z moves it again");

    // Save, then load in a fresh app.
    let file = dir.join("edited.ron");
    h.state_mut().save_scene_file(&file).unwrap();
    let saved_lights = h.state().session.lights.clone();
    let saved_camera = h.state().session.camera.camera();
    let mut fresh = reopen(&file, &dir);
    fresh.run_steps(2);
    assert_eq!(fresh.state().session.scene.name, "cornell");
    assert_eq!(fresh.state().session.lights, saved_lights);
    let c = fresh.state().session.camera.camera();
    assert!((c.position - saved_camera.position).length() < 1e-4, "{} vs {}", c.position, saved_camera.position);
    assert!(c.forward().dot(saved_camera.forward()) > 0.99999);
    assert!((c.fov_y - saved_camera.fov_y).abs() < 1e-6 && (c.z_far - saved_camera.z_far).abs() < 1e-4);
}

#[test]
fn a_broken_scene_file_keeps_the_current_scene() {
    let dir = data_dir("broken");
    let mut h = start("broken", "restaurant");
    let bad = dir.join("bad.ron");
    std::fs::write(&bad, "(version: 1, scene: Builtin(\"cornell\"), lights: [ (position: (1, 2").unwrap();
    h.state_mut().open_path(&bad);
    h.run_steps(2);
    assert_eq!(h.state().session.scene.name, "restaurant");
    assert_eq!(h.state().session.lights.len(), 14);
    h.get_by_label_contains("bad.ron");
    let missing = dir.join("nope.obj");
    h.state_mut().open_path(&missing);
    h.run_steps(1);
    assert_eq!(h.state().session.scene.name, "restaurant");
}

#[test]
fn view_screenshot_writes_a_png_at_render_resolution() {
    let mut h = start("shot", "cornell");
    assert_screen_shows_the_screenshot(&mut h);
}

/// On the GL backend (llvmpipe's OpenGL 4.5 here), which a machine without Vulkan, Metal or DirectX 12 falls
/// back to: the app starts (its device asks for compute shaders, not WebGL2's limits) and the screen shows
/// the image it saves (GL cannot view the sRGB output as plain `Rgba8Unorm`; a copy is shown instead).
#[test]
fn app_on_the_gl_backend_shows_what_it_saves() {
    let mut h = Harness::builder()
        .with_size(egui::vec2(SIZE.0, SIZE.1))
        .wgpu_setup(shadowlab::gui::wgpu_setup_on(wgpu::Backends::GL))
        .with_max_steps(40)
        .build_eframe(move |cc| {
            let startup = Startup { data_dir: Some(data_dir("gl")), synchronous: true, ..Default::default() };
            ShadowLabApp::new(cc, startup).expect("the app starts on the GL backend")
        });
    h.run_steps(3);
    let backend = h.state().views.gpu.as_ref().expect("a GPU view").ctx.adapter_info.backend;
    assert_eq!(backend, wgpu::Backend::Gl, "the harness was asked for GL only");
    h.state_mut().load_builtin("cornell");
    h.run_steps(3);
    assert_screen_shows_the_screenshot(&mut h);
}

/// The view's screenshot is at render resolution, named after the scene and technique, and holds what the
/// screen shows.
fn assert_screen_shows_the_screenshot(h: &mut Harness<'static, ShadowLabApp>) {
    let path = h.state_mut().save_view_screenshot().unwrap();
    let img = image::open(&path).unwrap();
    let (w, _) = h.state().views.gpu.as_ref().unwrap().main.size;
    assert_eq!(img.width(), w);
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(name.contains("cornell") && name.contains("reference"), "{name}");
    // The screenshot holds the pixels the screen shows (the screen used to show them decoded once more,
    // darker): egui's own rendering of the window against the saved image, over the central half of the view
    // (box means, which resampling from render resolution to the view's pixels keeps) and at 9 points (most
    // equal to a neighbouring texel; the rest lie on edges, where the view filters).
    let shown = h.render().expect("kittest renders the window");
    let rect = h.state().views.last_viewport_rect.expect("the view was laid out");
    let ppp = h.ctx.pixels_per_point();
    let saved = img.to_rgba8();
    let (sw, sh) = (saved.width() as f32, saved.height() as f32);
    let mean = |img: &image::RgbaImage, x0: f32, y0: f32, x1: f32, y1: f32| {
        let mut sum = [0f64; 3];
        let mut n = 0f64;
        for y in y0 as u32..y1 as u32 {
            for x in x0 as u32..x1 as u32 {
                let p = img.get_pixel(x, y);
                for i in 0..3 {
                    sum[i] += p[i] as f64;
                }
                n += 1.0;
            }
        }
        sum.map(|v| v / n)
    };
    let on_screen = mean(
        &shown,
        (rect.left() + 0.25 * rect.width()) * ppp,
        (rect.top() + 0.25 * rect.height()) * ppp,
        (rect.left() + 0.75 * rect.width()) * ppp,
        (rect.top() + 0.75 * rect.height()) * ppp,
    );
    let in_file = mean(&saved, 0.25 * sw, 0.25 * sh, 0.75 * sw, 0.75 * sh);
    for i in 0..3 {
        assert!(
            (on_screen[i] - in_file[i]).abs() <= 2.0,
            "the screen's mean {on_screen:?} and the screenshot's {in_file:?} differ (channel {i})"
        );
    }
    let mut off: Vec<i32> = Vec::new();
    for fy in [0.3f32, 0.5, 0.7] {
        for fx in [0.3f32, 0.5, 0.7] {
            let a = shown.get_pixel(
                ((rect.left() + fx * rect.width()) * ppp) as u32,
                ((rect.top() + fy * rect.height()) * ppp) as u32,
            );
            let nearest = (-1i32..=1)
                .flat_map(|dy| (-1i32..=1).map(move |dx| (dx, dy)))
                .map(|(dx, dy)| {
                    let px = ((fx * sw) as i32 + dx).clamp(0, sw as i32 - 1) as u32;
                    let py = ((fy * sh) as i32 + dy).clamp(0, sh as i32 - 1) as u32;
                    let c = saved.get_pixel(px, py);
                    (0..3).map(|i| (a[i] as i32 - c[i] as i32).abs()).max().unwrap()
                })
                .min()
                .unwrap();
            off.push(nearest);
        }
    }
    off.sort();
    assert!(off[4] <= 1, "at most half of the points may differ by more than a step: {off:?}");
}

#[test]
fn difference_view_measures_the_technique_against_the_reference() {
    use shadowlab::gui::document::ViewMode;
    use shadowlab_core::technique::ParamValue;
    let mut h = start("difference", "cornell");
    h.state_mut().session.view.mode = ViewMode::Difference;
    h.run_steps(4);
    let d = h.state().views.difference.as_ref().expect("a difference once both images are complete");
    assert_eq!(d.metrics.rmse, 0.0, "the reference against itself");
    let app = h.state_mut();
    app.session.technique = "lightcluster".into();
    app.session.params.entry("lightcluster".into()).or_default().insert("d_init".into(), ParamValue::Float(0.6));
    h.run_steps(4);
    let m = &h.state().views.difference.as_ref().unwrap().metrics;
    assert!(m.rmse > 0.0 && m.pixels > 1000, "LightCluster differs from the reference: {m:?}");
    h.state_mut().chrome.layout.focus(Pane::Render);
    h.run_steps(1);
    h.get_by_label("RMSE");
    // The session's comparison table has both techniques, of one view, so the speedup is shown.
    let times = &h.state().views.session_times;
    let lc = times.entries().find(|e| e.key == "lightcluster" && e.parameters.contains("d_init=0.6"));
    let lc = lc.unwrap_or_else(|| panic!("{times:?}"));
    let rows = times.rows(lc.view, "reference");
    let row = rows.iter().find(|r| r.entry.key == "lightcluster").unwrap();
    assert!(row.speedup.is_some(), "the two views measured one configuration: {times:?}");
    h.get_by_label("technique (this view)");
    // The panel names its clock, what the speedup compares, and the frame's work counts.
    assert!(h.query_all_by_label_contains("(SHADOWLAB_TIMING=").count() >= 1, "the clock is named");
    h.get_by_label_contains("speedup = the reference frame");
    h.get_by_label("work counts (hardware-independent)");
    // Maps at two resolutions are named, and "match" gives the reference the technique's.
    let app = h.state_mut();
    app.session.params.entry("lightcluster".into()).or_default().insert("shadow_res".into(), ParamValue::Int(64));
    app.session.params.entry("reference".into()).or_default().insert("shadow_res".into(), ParamValue::Int(128));
    h.run_steps(2);
    h.get_by_label_contains("maps not at one resolution: lightcluster 64², reference 128²");
    h.get_by_label("match").scroll_to_me();
    h.run_steps(3);
    h.get_by_label("match").click_accesskit();
    h.run_steps(2);
    assert_eq!(h.state().session.params["reference"]["shadow_res"], ParamValue::Int(64));
    assert_eq!(h.query_all_by_label_contains("maps not at one resolution").count(), 0);
    // Against the ray-traced ground truth instead: the reference itself differs a little.
    let app = h.state_mut();
    app.session.technique = "reference".into();
    app.session.view.compare_against = "raytraced".into();
    h.run_steps(4);
    assert_eq!(h.query_all_by_label_contains("maps not at one resolution").count(), 0, "the ray tracer has no maps");
    let m = &h.state().views.difference.as_ref().unwrap().metrics;
    assert!(m.rmse > 0.0 && m.share_over_threshold < 0.05, "reference vs ray traced: {m:?}");
    assert!(h.state().views.session_times.entries().any(|e| e.key == "raytraced"));
}

#[test]
fn sweep_panel_runs_in_the_background_and_can_be_cancelled() {
    use shadowlab_core::technique::ParamValue;
    let mut h = start("sweep", "cornell");
    h.state_mut().session.technique = "lightcluster".into();
    h.run_steps(2);
    let values: Vec<ParamValue> = [0.3f32, 0.45, 0.6].iter().map(|v| ParamValue::Float(*v)).collect();
    h.state_mut().start_sweep("d_init", values).unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while h.state_mut().views.sweep.as_mut().unwrap().poll() {
        assert!(std::time::Instant::now() < deadline, "the sweep did not finish");
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let s = h.state().views.sweep.as_ref().unwrap();
    assert!(s.worker.error.is_none(), "{:?}", s.worker.error);
    assert_eq!(s.rows.len(), 3);
    assert!(s.rows.windows(2).all(|w| w[0].value < w[1].value));
    assert!(s.rows.iter().all(|r| r.ms > 0.0 && r.rmse > 0.0 && r.reference_ms > 0.0));
    // Cancelled right away, a long sweep stops early.
    let many: Vec<ParamValue> = (0..40).map(|i| ParamValue::Float(0.1 + i as f32 * 0.05)).collect();
    h.state_mut().start_sweep("d_init", many).unwrap();
    h.state().views.sweep.as_ref().unwrap().cancel();
    while h.state_mut().views.sweep.as_mut().unwrap().poll() {
        assert!(std::time::Instant::now() < deadline + std::time::Duration::from_secs(60));
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    assert!(h.state().views.sweep.as_ref().unwrap().rows.len() < 40);
}

#[test]
fn lightcluster_offers_a_per_pixel_cluster_id_map() {
    let mut h = start("idmap", "cornell");
    h.state_mut().session.technique = "lightcluster".into();
    h.run_steps(3);
    assert!(h.state_mut().overlay_layers().iter().any(|(name, on)| name == "cluster per pixel" && !on));
    h.state_mut().session.view.overlays.insert("cluster per pixel".into(), true);
    h.run_steps(3);
    let (_, name, ids, (w, hgt)) = h.state().views.pixel_ids.clone().expect("an ID map once the frame is complete");
    assert_eq!(name, "cluster per pixel");
    assert_eq!(ids.len(), (w * hgt) as usize);
    let clusters =
        h.state().views.gpu.as_ref().unwrap().main.last_report.as_ref().unwrap().counts.technique.clusters.unwrap();
    let distinct: std::collections::BTreeSet<u32> = ids.iter().copied().filter(|&i| i != u32::MAX).collect();
    assert!(distinct.len() > 1 && distinct.iter().all(|&i| (i as usize) < clusters), "{distinct:?} of {clusters}");
}

/// Drag the gizmo's X handle at `at` by 60 points, in small moves.
fn drag_x_handle(h: &mut Harness<'static, ShadowLabApp>, at: glam::Vec3) {
    let (grab, dir_on_screen) = grab_x_handle(h, at);
    press(h, grab + dir_on_screen * 60.0, false, egui::Modifiers::NONE);
}

/// Press on the gizmo's X handle at `at` and move it by 60 points in small moves, without releasing it:
/// returns where it was grabbed and the handle's direction on screen.
fn grab_x_handle(h: &mut Harness<'static, ShadowLabApp>, at: glam::Vec3) -> (egui::Pos2, egui::Vec2) {
    let p = projection(h);
    let center = p.to_screen(at).expect("the gizmo is on screen");
    let grab = (0..360)
        .step_by(5)
        .flat_map(|a| [35.0, 45.0, 55.0].map(|r| center + egui::Vec2::angled((a as f32).to_radians()) * r))
        .find(|&q| gizmo::hit_handle(&p, at, q) == Some(gizmo::Handle::Axis(0)))
        .expect("the x handle is on screen");
    move_to(h, grab);
    press(h, grab, true, egui::Modifiers::NONE);
    let dir_on_screen = (grab - center).normalized();
    for i in 1..=6 {
        move_to(h, grab + dir_on_screen * (10.0 * i as f32));
    }
    (grab, dir_on_screen)
}

/// The points of a layer of the main view's `technique` for the session's lights.
fn layer_points(h: &mut Harness<'static, ShadowLabApp>, technique: &str, layer: &str) -> Vec<glam::Vec3> {
    let lights = h.state().session.lights.clone();
    let gpu = h.state_mut().views.gpu.as_mut().unwrap();
    let layers = gpu.main.technique(technique).unwrap().overlays(&lights);
    let layer = layers.into_iter().find(|l| l.name == layer).expect("the layer");
    layer
        .primitives
        .iter()
        .filter_map(|o| match o {
            shadowlab_core::technique::Overlay::Point { position, .. } => Some(*position),
            _ => None,
        })
        .collect()
}

#[test]
fn cluster_overlays_follow_a_dragged_light_before_it_is_released() {
    let mut h = start("drag-clusters", "cornell");
    h.state_mut().session.technique = "lightcluster".into();
    h.run_steps(4);
    // A light that is a cluster's center, on screen: its cluster center moves with it only if the clustering
    // runs again while it is dragged (the full frame waits for the release).
    let centers = layer_points(&mut h, "lightcluster", "cluster centers");
    let p = projection(&h);
    let rect = h.state().views.last_viewport_rect.unwrap().shrink(120.0);
    let index = h
        .state()
        .session
        .lights
        .iter()
        .position(|l| centers.contains(&l.position) && p.to_screen(l.position).is_some_and(|s| rect.contains(s)))
        .expect("a cluster center on screen");
    h.state_mut().session.selected = Some(index);
    h.run_steps(3);
    let before = h.state().session.lights[index].position;
    let (grab, dir) = grab_x_handle(&mut h, before);
    let moved = h.state().session.lights[index].position;
    assert!((moved - before).length() > 1e-3, "the light moves while the handle is held");
    let during = layer_points(&mut h, "lightcluster", "cluster centers");
    assert!(
        during.iter().any(|c| (*c - moved).length() < 1e-4),
        "the cluster center follows the dragged light before the release: {moved:?} not in {during:?}"
    );
    assert!(!during.iter().any(|c| (*c - before).length() < 1e-4), "no center is left where the light was");
    // The legend does not call LightCluster's layers stale; after the release the full frame agrees.
    assert!(h.state().views.legends.iter().all(|(_, e)| e.iter().all(|e| e.text != shadowlab::gui::views::STALE_NOTE)));
    press(&mut h, grab + dir * 60.0, false, egui::Modifiers::NONE);
    h.run_steps(4);
    let after = layer_points(&mut h, "lightcluster", "cluster centers");
    let released = h.state().session.lights[index].position;
    assert!(after.iter().any(|c| (*c - released).length() < 1e-4));
}

#[test]
fn an_indirect_technique_is_compared_with_its_own_target() {
    use shadowlab::gui::document::ViewMode;
    let mut h = start("indirect-target", "cornell");
    {
        let s = &mut h.state_mut().session;
        s.technique = "reference".into();
        s.indirect.vpl.count = 64;
        s.indirect.technique = Some("val".into());
        s.indirect.component = shadowlab_core::renderer::Component::Indirect;
        s.view.mode = ViewMode::Difference;
    }
    h.run_steps(8);
    let rmse =
        |h: &Harness<'static, ShadowLabApp>| h.state().views.difference.as_ref().expect("a difference").metrics.rmse;
    let target = |h: &Harness<'static, ShadowLabApp>| {
        let report = h.state().views.gpu.as_ref().unwrap().reference.last_report.clone().expect("a target frame");
        report.indirect.map(|i| i.technique)
    };
    // The indirect light alone: by default against VALs' declared target, one shadow map per VPL (the same
    // technique on both sides, the default before, differed by nothing: RMSE 0 whatever VALs did).
    assert_eq!(target(&h).as_deref(), Some("vpl-shadowmaps"));
    assert!(rmse(&h) > 1e-4, "val against vpl-shadowmaps: {}", rmse(&h));
    // The whole image: against the same indirect light (the direct techniques compared), the same frame here.
    h.state_mut().session.indirect.component = shadowlab_core::renderer::Component::Total;
    h.run_steps(8);
    assert_eq!(target(&h).as_deref(), Some("val"));
    assert!(rmse(&h) < 1e-5, "reference + val against reference + val: {}", rmse(&h));
    // A target the user chooses stands, and is saved.
    h.state_mut().session.indirect.component = shadowlab_core::renderer::Component::Indirect;
    h.state_mut().session.view.against_indirect = Some("vpl-shadowmaps".into());
    h.run_steps(8);
    assert_eq!(target(&h).as_deref(), Some("vpl-shadowmaps"));
    // Saved in the scene file and loaded again.
    let file = data_dir("indirect-target").join("target.ron");
    h.state_mut().save_scene_file(&file).unwrap();
    let mut fresh = start("indirect-target-load", "cornell");
    fresh.state_mut().load_scene_file(&file).unwrap();
    assert_eq!(fresh.state().session.view.against_indirect.as_deref(), Some("vpl-shadowmaps"));
}

#[test]
fn insm_viewpoints_are_edited_with_the_gizmo_and_saved_in_the_scene_file() {
    use shadowlab_core::technique::ParamValue;
    let dir = data_dir("insm");
    let mut h = start("insm", "arcade");
    h.state_mut().session.technique = "insm".into();
    // The paper's cameras on the bounding box, inside the default view (the default distance puts them outside).
    let params = h.state_mut().session.params.entry("insm".into()).or_default();
    params.insert("box_distance".into(), ParamValue::Float(1.0));
    h.run_steps(4);
    assert!(h.state_mut().overlay_layers().iter().any(|(name, on)| name == "INSM viewpoints" && *on));
    assert!(h.state_mut().overlay_layers().iter().any(|(name, _)| name == "INSM dropped edges"));

    // Start from the placed viewpoints: they become the custom list, and the placement switches to custom (the
    // button is scrolled into the panel first: INSM's parameters fill more than the panel's height).
    h.get_by_label("Edit the placed ones").scroll_to_me();
    h.run_steps(3);
    h.get_by_label("Edit the placed ones").click();
    h.run_steps(3);
    let cameras = |h: &Harness<'static, ShadowLabApp>| match h.state().session.params["insm"].get("viewpoints") {
        Some(ParamValue::Cameras(c)) => c.clone(),
        other => panic!("no custom viewpoints: {other:?}"),
    };
    assert_eq!(cameras(&h).len(), 10, "the paper's 10 viewpoints");
    assert_eq!(h.state().session.params["insm"]["placement"], ParamValue::Choice("custom".into()));

    // Select a viewpoint that is on screen by clicking it, then move it along x with the gizmo.
    let p = projection(&h);
    let rect = h.state().views.last_viewport_rect.unwrap().shrink(70.0);
    let (index, pos) = cameras(&h)
        .iter()
        .enumerate()
        .find_map(|(i, c)| p.to_screen(c.position).filter(|s| rect.contains(*s)).map(|s| (i, s)))
        .expect("a viewpoint is on screen");
    move_to(&mut h, pos);
    press(&mut h, pos, true, egui::Modifiers::NONE);
    press(&mut h, pos, false, egui::Modifiers::NONE);
    assert_eq!(
        h.state().session.selected_camera,
        Some(("viewpoints".to_string(), index)),
        "a click selects the viewpoint"
    );
    let before = cameras(&h)[index];
    drag_x_handle(&mut h, before.position);
    let after = cameras(&h)[index];
    assert!((after.position.x - before.position.x).abs() > 0.01, "{before:?} -> {after:?}");
    assert!((after.position.y - before.position.y).abs() < 1e-5, "only along x");
    assert!(
        ((after.target - after.position) - (before.target - before.position)).length() < 1e-4,
        "same view direction"
    );
    h.run_steps(3);

    // Remove the first one from the list.
    h.get_all_by_label("Remove").next().expect("a remove button per viewpoint").scroll_to_me();
    h.run_steps(2);
    h.get_all_by_label("Remove").next().expect("a remove button per viewpoint").click();
    h.run_steps(2);
    let edited = cameras(&h);
    assert_eq!(edited.len(), 9);

    // Saved and reloaded with the scene file.
    let file = dir.join("insm.ron");
    h.state_mut().save_scene_file(&file).unwrap();
    let mut fresh = reopen(&file, &dir);
    fresh.run_steps(2);
    assert_eq!(fresh.state().session.technique, "insm");
    assert_eq!(fresh.state().session.params["insm"]["viewpoints"], ParamValue::Cameras(edited.clone()));

    // A file whose viewpoint is out of range is refused with the parameter named; the loaded state stays.
    let text = std::fs::read_to_string(&file).unwrap();
    let fov = format!("fov_y_deg: {:?}", edited[0].fov_y_deg);
    assert!(text.contains(&fov), "{fov} not in the saved file");
    let bad = dir.join("insm-bad.ron");
    std::fs::write(&bad, text.replacen(&fov, "fov_y_deg: 500.0", 1)).unwrap();
    let err = fresh.state_mut().load_scene_file(&bad).unwrap_err();
    assert!(format!("{err:#}").contains("viewpoints"), "{err:#}");
    assert_eq!(fresh.state().session.params["insm"]["viewpoints"], ParamValue::Cameras(edited));
}

#[test]
fn indirect_light_is_chosen_in_its_selector_reported_compared_and_saved() {
    use shadowlab::gui::document::ViewMode;
    use shadowlab_core::renderer::Component;
    use shadowlab_core::technique::registry::INDIRECT_REGISTRY;
    use shadowlab_core::technique::ParamValue;
    let dir = data_dir("indirect");
    let mut h = start("indirect", "cornell");
    assert!(
        h.state().views.gpu.as_ref().unwrap().main.last_report.as_ref().unwrap().indirect.is_none(),
        "none at start"
    );
    h.state_mut().session.indirect.vpl.count = 48;
    // Choose it in the selector, by the registry's label.
    let entry = INDIRECT_REGISTRY.iter().find(|e| e.key == "vpl-unshadowed").expect("registered");
    h.get_by_label("Indirect").click();
    h.run_steps(2);
    h.get_by_label(entry.label).click();
    h.run_steps(4);
    assert_eq!(h.state().session.indirect.technique.as_deref(), Some(entry.key));
    let report = h.state().views.gpu.as_ref().unwrap().main.last_report.clone().expect("a complete frame");
    let indirect = report.indirect.expect("the report has the indirect technique");
    assert_eq!(indirect.technique, entry.key);
    assert!(indirect.vpls > 0 && indirect.vpls <= 48, "{} VPLs", indirect.vpls);
    assert_eq!(indirect.counts.figures.get("vpls"), Some(&(indirect.vpls as f64)));
    // The timings panel lists its figures, and its parameters have their own panel.
    h.get_by_label_contains(&format!("indirect {} · vpls {}", entry.key, indirect.vpls));
    assert!(h.query_all_by_label("VPLs per step").count() >= 1, "its parameter panel");
    // Its overlay layers are listed with the direct technique's.
    let layers = h.state_mut().overlay_layers();
    assert!(layers.iter().any(|(name, _)| name.starts_with("vpls (flux")), "{layers:?}");

    // The indirect component alone is not black; the comparison view renders the same indirect light when
    // asked to (its default there is the technique's own target).
    let app = h.state_mut();
    app.session.indirect.component = Component::Indirect;
    app.session.view.against_indirect = Some(entry.key.into());
    app.session
        .indirect
        .params
        .entry(entry.key.into())
        .or_default()
        .insert("vpls_per_step".into(), ParamValue::Int(16));
    app.session.view.mode = ViewMode::SideBySide;
    h.run_steps(6);
    let gpu = h.state().views.gpu.as_ref().unwrap();
    let main = gpu.main.last_report.as_ref().unwrap().indirect.clone().unwrap();
    let reference = gpu.reference.last_report.as_ref().unwrap().indirect.clone().expect("the reference view too");
    assert_eq!((reference.technique.as_str(), reference.vpls), (entry.key, main.vpls));
    assert_eq!(main.counts.batches, main.vpls.div_ceil(16), "the parameter reached the renderer");
    assert_eq!(reference.counts.batches, main.counts.batches, "and the reference view's");
    let hdr = gpu.main.renderer.read_component(Component::Indirect).unwrap();
    assert!(hdr.iter().any(|p| p[0] + p[1] + p[2] > 0.0), "some indirect light");

    // While the camera moves the preview has no indirect light; once it settles the same instance is back.
    let centre = h.state().views.last_viewport_rect.unwrap().center();
    move_to(&mut h, centre);
    h.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, 40.0),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Wheel,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    h.step();
    let preview = h.state().views.gpu.as_ref().unwrap().main.last_report.clone().unwrap();
    assert!(preview.technique == "unshadowed" && preview.indirect.is_none(), "{}", preview.technique);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    let settled = loop {
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.step();
        let r = h.state().views.gpu.as_ref().unwrap().main.last_report.clone().unwrap();
        if r.technique != "unshadowed" || std::time::Instant::now() > deadline {
            break r;
        }
    };
    assert_eq!(settled.technique, "reference");
    assert_eq!(settled.indirect.expect("indirect light again").counts.batches, main.counts.batches);

    // Saved and loaded in a fresh app; a file naming an unknown indirect technique is refused, state kept.
    let file = dir.join("indirect.ron");
    h.state_mut().save_scene_file(&file).unwrap();
    let saved = h.state().session.indirect.clone();
    let mut fresh = reopen(&file, &dir);
    fresh.run_steps(3);
    assert_eq!(fresh.state().session.indirect, saved);
    let report = fresh.state().views.gpu.as_ref().unwrap().main.last_report.clone().unwrap();
    assert_eq!(report.indirect.map(|i| i.technique), Some(entry.key.to_string()));
    let text = std::fs::read_to_string(&file).unwrap();
    let bad = dir.join("indirect-bad.ron");
    std::fs::write(&bad, text.replace("\"vpl-unshadowed\"", "\"vpl-nonsense\"")).unwrap();
    let err = fresh.state_mut().load_scene_file(&bad).unwrap_err();
    assert!(format!("{err:#}").contains("unknown indirect technique 'vpl-nonsense'"), "{err:#}");
    assert_eq!(fresh.state().session.indirect, saved);
}

#[test]
fn the_app_can_start_with_an_indirect_technique() {
    let mut h =
        started("startup-indirect", Some("cornell"), StartState { indirect: Some("val".into()), ..Default::default() });
    h.run_steps(3);
    assert_eq!(h.state().session.indirect.technique.as_deref(), Some("val"));
    assert!(h.query_all_by_label_contains("VALs (M)").count() >= 1, "the VAL parameter panel is shown");
    // An unknown key is a message, not a panic, and no indirect technique.
    let mut bad =
        started("startup-indirect-bad", None, StartState { indirect: Some("magic".into()), ..Default::default() });
    bad.run_steps(2);
    assert!(bad.state().session.indirect.technique.is_none());
    bad.get_by_label_contains("unknown indirect technique 'magic'");
    // With the indirect light alone (`--app-component indirect`): against VALs' own target, said in the exit line.
    let start = StartState {
        indirect: Some("val".into()),
        component: Some("indirect".into()),
        view: Some("difference".into()),
        ..Default::default()
    };
    let mut alone = started("startup-indirect-alone", Some("cornell"), start);
    alone.state_mut().session.indirect.vpl.count = 64;
    alone.run_steps(8);
    assert_eq!(alone.state().session.indirect.component, shadowlab_core::renderer::Component::Indirect);
    let line = alone.state().exit_line();
    assert!(line.contains("component=indirect") && line.contains("indirect=vpl-shadowmaps"), "{line}");
    let mut wrong =
        started("startup-component-bad", None, StartState { component: Some("both".into()), ..Default::default() });
    wrong.run_steps(2);
    wrong.get_by_label_contains("--app-component 'both': choose total, direct, indirect");
}

#[test]
fn fuzzy_clustering_runs_in_the_app_and_alt_click_probes_a_pixel() {
    use shadowlab_core::technique::ParamValue;
    let mut h = start("fuzzy", "cornell");
    h.state_mut().session.indirect.vpl.count = 64;
    h.state_mut().session.indirect.technique = Some("fuzzy".into());
    h.run_steps(8);
    let report = h.state().views.gpu.as_ref().unwrap().main.last_report.clone().expect("a complete frame");
    let indirect = report.indirect.expect("fuzzy ran");
    assert_eq!(indirect.technique, "fuzzy");
    let figures = &indirect.counts.figures;
    assert!(figures["k_sp"] > 0.0 && figures["k_vpl"] > 0.0 && figures["shadow rays"] > 0.0, "{figures:?}");
    // Its layers are listed: VPL clusters and the per-pixel shading-point clusters.
    let layers = h.state_mut().overlay_layers();
    assert!(layers.iter().any(|(name, _)| name.starts_with("shading-point clusters")), "{layers:?}");
    // Alt+click in the view: the technique's probe parameters get the clicked pixel.
    let rect = h.state().views.last_viewport_rect.expect("the view was laid out");
    let pos = rect.center();
    h.event(egui::Event::ModifiersChanged(egui::Modifiers::ALT));
    press(&mut h, pos, true, egui::Modifiers::ALT);
    press(&mut h, pos, false, egui::Modifiers::ALT);
    h.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
    h.run_steps(8);
    let params = h.state().session.indirect.params.get("fuzzy").cloned().unwrap_or_default();
    let (x, y) = (params.get("probe_x"), params.get("probe_y"));
    assert!(matches!(x, Some(ParamValue::Int(v)) if *v > 0), "probe_x {x:?}");
    assert!(matches!(y, Some(ParamValue::Int(v)) if *v > 0), "probe_y {y:?}");
    // The probe layer then holds the pixel's clusters and their rays.
    let gpu = h.state_mut().views.gpu.as_mut().unwrap();
    let technique = gpu.main.indirect_technique("fuzzy").unwrap();
    let layers = technique.borrow().overlays(&[]);
    let probe = layers.iter().find(|l| l.name.starts_with("probe")).expect("a probe layer");
    assert!(probe.primitives.len() > 1, "the probe shows nothing");
    // And the VPL source switched to the paper's traced particles when fuzzy was chosen at startup only; here
    // it was set in code, so the user's source is kept.
    assert_eq!(h.state().session.indirect.vpl.source, shadowlab_core::vpl::VplSource::Rsm);
}

#[test]
fn every_techniques_parameter_panel_draws_without_a_panic() {
    // Generated panels for every registered technique and indirect technique: a slider with a range egui
    // refuses (e.g. logarithmic across zero) panics the whole app, so each panel is drawn once here.
    let mut h = start("panels", "cornell");
    h.state_mut().session.indirect.vpl.count = 16;
    for entry in shadowlab_core::technique::registry::REGISTRY {
        h.state_mut().session.technique = entry.key.to_string();
        h.run_steps(2);
    }
    h.state_mut().session.technique = "unshadowed".into();
    for entry in shadowlab_core::technique::registry::INDIRECT_REGISTRY {
        h.state_mut().session.indirect.technique = Some(entry.key.to_string());
        h.run_steps(2);
        // The selector names it; its generated panel shows its first parameter.
        assert!(h.query_all_by_label_contains(entry.key).count() >= 1, "{}: not selected", entry.key);
    }
}

/// The share of the window the 3D view's rect covers.
fn view_share(h: &Harness<'static, ShadowLabApp>, size: (f32, f32)) -> f32 {
    let r = h.state().views.last_viewport_rect.expect("the view was laid out");
    r.area() / (size.0 * size.1)
}

#[test]
fn the_default_layout_gives_the_view_most_of_the_window() {
    for size in [(1024.0, 640.0), (1400.0, 860.0)] {
        let mut h = harness_sized(
            Startup {
                data_dir: Some(data_dir(&format!("layout-{}", size.0))),
                synchronous: true,
                builtin: Some("cornell".into()),
                ..Default::default()
            },
            size,
        );
        h.run_steps(2);
        let share = view_share(&h, size);
        assert!(share >= 0.6, "the view covers {:.1} % of a {}x{} window", share * 100.0, size.0, size.1);
        // The panels are still there: the technique selector and the timings.
        h.get_by_label("Technique");
        h.get_by_label_contains("adapter:");
    }
}

#[test]
fn full_view_hides_every_panel_and_tab_brings_them_back() {
    let mut h = start("full-view", "cornell");
    h.get_by_label("Technique");
    h.key_press(egui::Key::Tab);
    h.run_steps(2);
    assert!(h.state().chrome.layout.full_view);
    assert_eq!(h.query_all_by_label("Technique").count(), 0, "the technique panel is hidden");
    assert_eq!(h.query_all_by_label_contains("adapter:").count(), 0, "the timings panel is hidden");
    assert_eq!(h.query_all_by_label("File").count(), 0, "the menu bar is hidden");
    let share = view_share(&h, SIZE);
    assert!(share > 0.97, "the view fills the window in full view: {:.1} %", share * 100.0);
    h.key_press(egui::Key::F11);
    h.run_steps(2);
    assert!(!h.state().chrome.layout.full_view);
    h.get_by_label("Technique");
    // The button over the view leaves full view too.
    h.key_press(egui::Key::F11);
    h.run_steps(2);
    h.get_by_label("Show panels (Tab)").click();
    h.run_steps(2);
    h.get_by_label("Technique");
}

#[test]
fn a_hidden_panel_is_restored_from_the_menu_and_the_layout_is_saved() {
    let dir = data_dir("layout-saved");
    let mut h = harness(Startup {
        data_dir: Some(dir.clone()),
        synchronous: true,
        builtin: Some("cornell".into()),
        ..Default::default()
    });
    let before = view_share(&h, SIZE);
    // Hide the column's lower tab group (timings) with its tab bar's button.
    h.get_by_label("Timings").click();
    h.run_steps(1);
    let hide: Vec<_> = h.get_all_by_label("hide").collect();
    assert_eq!(hide.len(), 2, "one hide button per tab bar");
    // The lower one: the timings' tab bar is right above the timings.
    let timings = h.state().chrome.layout.rect(Pane::Timings).unwrap();
    let lower = hide.into_iter().max_by(|a, b| a.rect().center().y.total_cmp(&b.rect().center().y)).unwrap();
    assert!((lower.rect().center().y - timings.top()).abs() < 30.0, "{:?} vs {timings:?}", lower.rect());
    lower.click();
    h.run_steps(3);
    assert!(!h.state().chrome.layout.is_shown(Pane::Timings));
    assert_eq!(h.query_all_by_label_contains("adapter:").count(), 0, "the timings panel is hidden");
    // Saved as it changed: a new app opens with the same layout.
    let mut fresh = harness(Startup { data_dir: Some(dir.clone()), synchronous: true, ..Default::default() });
    fresh.run_steps(2);
    assert!(!fresh.state().chrome.layout.is_shown(Pane::Timings), "the layout was saved with the app state");
    assert!(fresh.state().chrome.layout.is_shown(Pane::Lights));
    // The Panels menu shows it again.
    fresh.get_by_label("Panels").click();
    fresh.run_steps(2);
    fresh.get_by_label("Timings").click();
    fresh.run_steps(2);
    assert!(fresh.state().chrome.layout.is_shown(Pane::Timings));
    fresh.get_by_label_contains("adapter:");
    assert!(before > 0.6);
}

#[test]
fn a_visible_layer_shows_its_legend_and_a_light_its_cluster() {
    let mut h = start("legend", "cornell");
    h.state_mut().session.technique = "lightcluster".into();
    h.run_steps(3);
    h.state_mut().chrome.layout.focus(Pane::Overlays);
    h.run_steps(2);
    // "lights by cluster" is on by default: its legend is listed under its checkbox.
    h.get_by_label_contains("in its cluster's colour");
    let names: Vec<String> = h.state().views.legends.iter().map(|(n, _)| n.clone()).collect();
    assert!(names.iter().any(|n| n == "lights by cluster"), "{names:?}");
    assert!(!names.iter().any(|n| n == "d_min spheres"), "a hidden layer has no legend: {names:?}");
    assert_eq!(h.query_all_by_label_contains("disc-light radius").count(), 0);
    h.state_mut().session.view.overlays.insert("d_min spheres".into(), true);
    h.run_steps(3);
    let legends = &h.state().views.legends;
    let d_min = legends.iter().find(|(n, _)| n == "d_min spheres").expect("shown now, with its legend");
    assert!(d_min.1.iter().any(|e| e.text.contains("disc-light radius")), "{:?}", d_min.1);
    // A light's tooltip names its cluster; selecting it selects the cluster's members for highlighting.
    let lines = h.state_mut().light_tooltip(0);
    assert!(lines.iter().any(|l| l.starts_with("cluster ")) && lines[0] == "light 0", "{lines:?}");
    let group = h.state_mut().light_details(0).expect("light 0 is in a cluster").group;
    assert!(group.contains(&0));
}

#[test]
fn figure_export_writes_three_captioned_panes_and_sequences_their_pngs_and_gifs() {
    use shadowlab::figure::{figure_size, GAP, TITLE_HEIGHT};
    use shadowlab_core::technique::ParamValue;
    let mut h = start("figure", "cornell");
    let app = h.state_mut();
    app.session.technique = "lightcluster".into();
    app.session.params.entry("lightcluster".into()).or_default().insert("d_init".into(), ParamValue::Float(0.6));
    h.run_steps(3);
    let path = h.state_mut().save_figure().unwrap();
    let (w, hgt) = h.state().views.gpu.as_ref().unwrap().main.size;
    let img = image::open(&path).unwrap().to_rgb8();
    // Three panes of the view's render size (captions that wrap make it taller).
    let (fw, fh) = figure_size(w, hgt, 3);
    assert!(img.width() == fw && img.height() >= fh, "{:?} against {fw}x{fh}", img.dimensions());
    assert!(path.file_name().unwrap().to_string_lossy().contains("figure"));
    // Three different images: the technique, the reference, the difference (mostly dark blue).
    let mean = |pane: u32| {
        let x0 = GAP + pane * (w + GAP);
        let mut sum = [0f64; 3];
        for y in TITLE_HEIGHT..TITLE_HEIGHT + hgt {
            for x in x0..x0 + w {
                let p = img.get_pixel(x, y).0;
                (0..3).for_each(|c| sum[c] += p[c] as f64);
            }
        }
        sum.map(|s| s / (w * hgt) as f64)
    };
    let (t, r, d) = (mean(0), mean(1), mean(2));
    assert!(t != r, "LightCluster differs from the reference: {t:?} {r:?}");
    assert!(d[2] > d[0] && d[0] < 100.0, "the difference is mostly dark blue: {d:?}");
    assert!(t.iter().all(|c| *c < 250.0), "the panes are not the white background: {t:?}");
    // An orbit of 3 frames: 3 PNGs at the render size, not all the same, and a GIF of the 3.
    let orbit = h.state_mut().save_sequence(Motion::Orbit, 3).unwrap();
    assert_eq!(orbit.frames.len(), 3);
    let images: Vec<_> = orbit.frames.iter().map(|f| image::open(f).unwrap().to_rgba8()).collect();
    assert!(images.iter().all(|i| i.dimensions() == (w, hgt)));
    assert!(images[0] != images[1], "the camera moved between frames");
    let gif = gif_frames(&orbit.gif);
    assert_eq!(gif.len(), 3, "one GIF frame per PNG");
    assert!(gif.iter().all(|f| f.buffer().dimensions() == (w, hgt)));
    assert!(h.state_mut().save_sequence(Motion::Orbit, 0).is_err(), "no frames is an error, not a panic");
    // The view's overlay layers (LightCluster's lights by cluster) are drawn over the frames, unless switched off.
    h.state_mut().chrome.sequence_overlays = false;
    let plain = h.state_mut().save_sequence(Motion::Orbit, 3).unwrap();
    let plain: Vec<_> = plain.frames.iter().map(|f| image::open(f).unwrap().to_rgba8()).collect();
    assert!(plain[0] != images[0] && plain[0].dimensions() == images[0].dimensions(), "overlays drawn");
    h.state_mut().chrome.sequence_overlays = true;
    // The light animation: an error while it is off, then one period in 2 frames that differ.
    assert!(h.state_mut().save_sequence(Motion::Lights, 2).is_err(), "the animation is off");
    h.state_mut().session.animation = shadowlab::gui::Animation::Bob;
    let lights = h.state_mut().save_sequence(Motion::Lights, 2).unwrap();
    let images: Vec<_> = lights.frames.iter().map(|f| image::open(f).unwrap().to_rgba8()).collect();
    assert!(images[0] != images[1], "the lights moved between frames");
    assert_eq!(gif_frames(&lights.gif).len(), 2);
    assert!(lights.gif.parent() != orbit.gif.parent(), "each sequence in a folder of its own");
}

fn gif_frames(path: &std::path::Path) -> Vec<image::Frame> {
    use image::AnimationDecoder;
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    image::codecs::gif::GifDecoder::new(file).unwrap().into_frames().collect_frames().unwrap()
}

#[test]
fn the_shadow_map_inspector_unfolds_a_cube_map_reads_distances_and_follows_the_selected_light() {
    let mut h = start("inspector-maps", "cornell");
    h.state_mut().chrome.layout.focus(Pane::Maps);
    h.run_steps(3);
    let app = h.state();
    let atlas = app.chrome.inspector.atlas.as_ref().expect("the reference's atlas was read back");
    assert!(atlas.tiles >= 6 && atlas.resolution == 256, "{} tiles of {}", atlas.tiles, atlas.resolution);
    let cross = app.chrome.inspector.shown.as_ref().expect("a cube map is shown");
    assert_eq!((cross.width, cross.height), (4 * atlas.resolution, 3 * atlas.resolution), "unfolded as a cross");
    // Six faces of texels, outside them nothing; the light's walls within its range are drawn.
    let inside = cross.depths.iter().filter(|d| !d.is_nan()).count();
    assert_eq!(inside, 6 * (atlas.resolution * atlas.resolution) as usize);
    assert!(cross.depths.iter().any(|d| *d > 0.0 && *d < 1.0), "some geometry in the cube map");
    let centre = cross.readout(2 * atlas.resolution - atlas.resolution / 2, atlas.resolution * 3 / 2).unwrap();
    assert!(centre.contains("cube 0 face +z") && centre.contains("depth "), "{centre}");
    h.get_by_label_contains("tiles of 256² texels");
    // Selecting a light shows its cube map; the centre of its +y face sees the ceiling (the room's inside is
    // y in [0, 2]) straight above the light, and reads the distance to it.
    let lights = h.state().session.lights.clone();
    let (index, light) = lights
        .iter()
        .enumerate()
        .rfind(|(_, l)| 2.0 - l.position.y < 0.9 * l.range)
        .expect("a light whose range reaches the ceiling");
    h.state_mut().session.selected = Some(index);
    h.run_steps(2);
    let app = h.state();
    let cube = app.chrome.inspector.cube.expect("a cube map is shown");
    let atlas = app.chrome.inspector.atlas.as_ref().unwrap();
    assert_eq!(atlas.cube_at(light.position, 1e-4), Some(cube), "the selected light's cube map is shown");
    assert_eq!(app.chrome.inspector.note.as_deref(), Some(format!("light {index}: cube {cube}").as_str()));
    let r = atlas.resolution;
    let cross = app.chrome.inspector.shown.as_ref().unwrap();
    let (x, y) = (r + r / 2, r / 2);
    let readout = cross.readout(x, y).unwrap();
    assert!(readout.contains(&format!("cube {cube} face +y")), "{readout}");
    let distance = cross.distance(x, y).expect("the ceiling is within the light's range");
    let expected = 2.0 - light.position.y;
    assert!((distance - expected).abs() < 2e-3 * expected.max(1.0), "read {distance}, the ceiling is {expected} above");
    assert!(readout.contains(&format!("distance {distance:.3}")), "{readout}");
    // Linearised grey: the same texels drawn by distance.
    h.get_by_label("linearised grey").click();
    h.run_steps(2);
    assert!(h.state().chrome.inspector.linear && h.state().chrome.inspector.shown.is_some());
}

#[test]
fn the_inspector_lists_insms_intermediate_images_and_lightclusters_cluster_maps() {
    use shadowlab::gui::inspector::MapSource;
    let mut h = start("inspector-insm", "cornell");
    h.state_mut().session.technique = "insm".into();
    h.state_mut().chrome.layout.focus(Pane::Maps);
    h.run_steps(4);
    let images = MapSource { indirect: false, set: 1 };
    let sources = h.state().chrome.inspector.sources.clone();
    assert!(
        sources.iter().any(|(s, l)| *s == images && l.contains("intermediate depth images")),
        "INSM offers its intermediate images: {sources:?}"
    );
    assert!(sources.iter().any(|(s, l)| *s == MapSource::DIRECT && l.contains("shadow maps")), "{sources:?}");
    h.state_mut().chrome.inspector.source = images;
    h.run_steps(3);
    let viewpoints =
        h.state_mut().views.gpu.as_mut().unwrap().main.technique("insm").unwrap().cameras_in_use("viewpoints");
    let app = h.state();
    let atlas = app.chrome.inspector.atlas.as_ref().expect("the intermediate images were read back");
    assert_eq!(atlas.cubes(), 0, "views, not cube maps");
    // Each viewpoint's image is a tile seen from that viewpoint, its texels read as distances from it.
    let eyes: Vec<glam::Vec3> = atlas.projections.iter().flatten().map(|p| p.eye()).collect();
    assert_eq!(eyes.len(), viewpoints.len(), "one image per viewpoint");
    for v in &viewpoints {
        assert!(eyes.iter().any(|e| e.distance(v.position) < 1e-3), "no image from {:?}: {eyes:?}", v.position);
    }
    let shown = app.chrome.inspector.shown.as_ref().expect("the whole atlas is shown");
    let r = atlas.resolution;
    let readout = shown.readout(r / 2, r / 2).unwrap();
    let distance = shown.distance(r / 2, r / 2).expect("the first viewpoint sees the room");
    // Inside the 2 m room every surface is less than its diagonal (3.5 m) away, from a viewpoint at most ~2 m outside.
    assert!(readout.contains("tile 0 · view") && distance > 0.05 && distance < 6.0, "{readout}");
    // Explain step 3 (their meshes) turns `mesh_views` on and shows the meshes seen from the viewpoints.
    h.state_mut().chrome.layout.focus(Pane::Explain);
    h.run_steps(1);
    h.get_by_label("3. Their meshes").click();
    h.run_steps(5);
    let meshes = MapSource { indirect: false, set: 2 };
    let sources = h.state().chrome.inspector.sources.clone();
    assert!(sources.iter().any(|(s, l)| *s == meshes && l.contains("meshes seen from the viewpoints")), "{sources:?}");
    assert_eq!(h.state().chrome.inspector.source, meshes);
    let atlas = h.state().chrome.inspector.atlas.as_ref().expect("the meshes' views were read back");
    assert!(atlas.what.contains("meshes seen from the viewpoints") && atlas.depths.iter().any(|d| *d < 1.0));
    // The step's maps fill the 3D view (the panel's image, large) until the view is clicked.
    assert!(h.state().chrome.explain.map_in_view, "a step about maps shows them in the view");
    let (_, size, what) = h.state().chrome.inspector.on_screen(32).expect("the panel's image is on screen");
    assert!(size[0] > 0 && what.contains("meshes seen from the viewpoints"), "{what}");
    let centre = h.state().views.last_viewport_rect.expect("the view was laid out").center();
    let selected = h.state().session.selected;
    press(&mut h, centre, true, egui::Modifiers::NONE);
    press(&mut h, centre, false, egui::Modifiers::NONE);
    assert!(!h.state().chrome.explain.map_in_view, "a click returns to the scene");
    assert_eq!(h.state().session.selected, selected, "the click that closed the maps selected nothing");
    // LightCluster: a cube map per cluster; selecting a light shows its cluster's.
    h.state_mut().session.technique = "lightcluster".into();
    h.state_mut().chrome.inspector.source = MapSource::DIRECT;
    h.run_steps(4);
    let atlas = h.state().chrome.inspector.atlas.as_ref().expect("LightCluster's cube maps");
    assert!(atlas.cubes() > 0 && atlas.what.contains("per cluster"), "{}", atlas.what);
    h.state_mut().session.selected = Some(5);
    h.run_steps(2);
    let note = h.state().chrome.inspector.note.clone().unwrap_or_default();
    assert!(note.starts_with("light 5: cube "), "{note}");
    // The cube shown is rendered from a member of light 5's cluster (its center).
    let group = h.state_mut().light_details(5).expect("LightCluster knows light 5's cluster").group;
    let app = h.state();
    let (atlas, cube) = (app.chrome.inspector.atlas.as_ref().unwrap(), app.chrome.inspector.cube.unwrap());
    assert!(group.iter().any(|&m| atlas.cube_at(app.session.lights[m].position, 1e-4) == Some(cube)), "{group:?}");
}

#[test]
fn the_maps_panel_shows_a_lights_reflective_shadow_map_with_the_texels_its_vpls_came_from() {
    use shadowlab::gui::inspector::RSM_LABEL;
    use shadowlab::rsm_picture::RsmShow;
    use shadowlab_core::vpl::rsm::RsmLayout;
    let mut h = start("inspector-rsm", "cornell");
    h.state_mut().session.indirect.vpl.count = 256;
    h.state_mut().session.indirect.technique = Some("vpl-raytraced".into());
    h.state_mut().chrome.layout.focus(Pane::Maps);
    h.run_steps(4);
    // Chosen from the maps list, as a user would.
    h.get_by_label("maps").click();
    h.run_steps(2);
    h.get_by_label(RSM_LABEL).click();
    h.run_steps(2);
    assert!(h.state().chrome.inspector.rsm_shown);
    // Selecting a light shows its map: the Cornell box's lights are point lights, so a cube.
    h.state_mut().session.selected = Some(3);
    h.run_steps(3);
    let light = h.state().session.animated_lights()[3];
    let vpls = h.state().views.gpu.as_ref().unwrap().main.renderer.shared_vpls();
    let app = h.state();
    let rsm = &app.chrome.inspector.rsm;
    assert_eq!(rsm.emitter, 3, "the selected light's RSM");
    let image = rsm.image.as_ref().expect("the RSM was cast");
    assert_eq!(image.layout, RsmLayout::Cube { eye: light.position });
    assert_eq!((image.resolution, image.faces), (64, 6));
    // Inside the closed box a texel sees a wall unless the wall lies past the light's range.
    let seen: Vec<_> = image.texels.iter().flatten().collect();
    assert!(seen.len() * 2 > image.texels.len(), "{} of {} texels see a wall", seen.len(), image.texels.len());
    assert!(seen.iter().all(|t| t.distance <= light.range && t.flux.max_element() > 0.0));
    // The rings: every first-bounce VPL of light 3 is counted in a texel.
    let own = vpls.vpls.iter().filter(|v| v.light == 3).count();
    assert!(own > 0 && rsm.drawn.values().sum::<u32>() as usize == own, "{own} VPLs, {:?}", rsm.drawn.len());
    h.get_by_label_contains(&format!("of the frame's {} VPLs came from here", vpls.vpls.len()));
    h.get_by_label_contains("light 3: a cube of 6 x 64² texels");
    // The normal view, then a sun-less scene's last emitter is the last light.
    h.get_by_label("normal").click();
    h.run_steps(1);
    assert_eq!(h.state().chrome.inspector.rsm.show, RsmShow::Normal);
    // Back to the technique's maps: the reference's cube maps are read again.
    h.get_by_label("maps").click();
    h.run_steps(2);
    h.get_by_label_contains("shadow maps").click();
    h.run_steps(3);
    assert!(!h.state().chrome.inspector.rsm_shown && h.state().chrome.inspector.atlas.is_some());
    // The VPL techniques' first Explain step shows it again.
    h.state_mut().chrome.layout.focus(Pane::Explain);
    h.run_steps(1);
    h.get_by_label("1. Virtual point lights").click();
    h.run_steps(2);
    assert!(h.state().chrome.inspector.rsm_shown, "the VPL step shows the RSM");
    h.get_by_label_contains("of the frame's");
}

#[test]
fn every_explain_step_of_every_technique_draws_without_a_panic() {
    // A glyph egui's fonts lack (an arrow, say) in a step's text panics the app when the step is chosen.
    let mut h = start("explain-all", "cornell");
    h.state_mut().session.indirect.vpl.count = 16;
    let mut clicked = 0;
    let mut click_all = |h: &mut Harness<'static, ShadowLabApp>, titles: Vec<&'static str>| {
        h.state_mut().chrome.layout.focus(Pane::Explain);
        h.run_steps(1);
        for title in titles {
            h.get_by_label(title).click();
            h.run_steps(1);
            clicked += 1;
        }
    };
    for entry in shadowlab_core::technique::registry::REGISTRY {
        h.state_mut().session.technique = entry.key.to_string();
        h.run_steps(1);
        let steps = h.state_mut().views.gpu.as_mut().unwrap().main.technique(entry.key).unwrap().explain();
        click_all(&mut h, steps.iter().map(|s| s.title).collect());
    }
    h.state_mut().session.technique = "unshadowed".into();
    for entry in shadowlab_core::technique::registry::INDIRECT_REGISTRY {
        h.state_mut().session.indirect.technique = Some(entry.key.to_string());
        h.run_steps(1);
        let t = h.state_mut().views.gpu.as_mut().unwrap().main.indirect_technique(entry.key).unwrap();
        let titles: Vec<&'static str> = t.borrow().explain().iter().map(|s| s.title).collect();
        click_all(&mut h, titles);
    }
    assert!(clicked >= 20, "{clicked} steps");
}

#[test]
fn explain_steps_of_lightcluster_and_insm_switch_their_layers() {
    let mut h = start("explain", "cornell");
    h.state_mut().session.technique = "lightcluster".into();
    h.run_steps(3);
    h.state_mut().chrome.layout.focus(Pane::Explain);
    h.run_steps(1);
    h.get_by_label("2. Cluster centers").click();
    h.run_steps(2);
    let on = |h: &mut Harness<'static, ShadowLabApp>, name: &str| {
        h.state_mut().overlay_layers().into_iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("{name}")).1
    };
    assert!(on(&mut h, "cluster centers") && on(&mut h, "d_min spheres"));
    assert!(!on(&mut h, "member -> center") && !on(&mut h, "lights by cluster"));
    h.get_by_label_contains("from every center so far");
    // The cube-map step brings the shadow maps forward.
    h.get_by_label("4. One cube map per cluster").click();
    h.run_steps(2);
    assert!(h.state().chrome.layout.is_on_screen(Pane::Maps));
    // The visibility step draws one cluster's visibility alone; the next step restores the parameter.
    use shadowlab_core::technique::ParamValue;
    let visibility_of =
        |h: &Harness<'static, ShadowLabApp>| h.state().session.params["lightcluster"].get("visibility_of").cloned();
    h.get_by_label("5. Soft visibility per cluster").click();
    h.run_steps(2);
    assert_eq!(visibility_of(&h), Some(ParamValue::Int(0)));
    h.get_by_label("6. Final image").click();
    h.run_steps(2);
    assert_eq!(visibility_of(&h), Some(ParamValue::Int(-1)), "back to every cluster");
    // INSM: the mesh step shows the wireframe and the dropped edges.
    h.state_mut().session.technique = "insm".into();
    h.state_mut().chrome.layout.focus(Pane::Explain);
    h.run_steps(3);
    h.get_by_label("2. Intermediate depth images").click();
    h.run_steps(2);
    let images = shadowlab::gui::inspector::MapSource { indirect: false, set: 1 };
    assert!(h.state().chrome.layout.is_on_screen(Pane::Maps) && h.state().chrome.inspector.source == images);
    h.get_by_label("3. Their meshes").click();
    h.run_steps(2);
    assert!(on(&mut h, "INSM mesh (wireframe)") && on(&mut h, "INSM dropped edges") && !on(&mut h, "INSM viewpoints"));
    // A technique without steps says so.
    h.state_mut().session.technique = "unshadowed".into();
    h.run_steps(2);
    h.get_by_label_contains("describes no steps");
}

#[test]
fn explain_steps_of_val_and_fuzzy_set_the_parameters_that_show_them_and_give_them_back() {
    use shadowlab_core::technique::ParamValue;
    let mut h = start("explain-indirect", "cornell");
    h.state_mut().session.indirect.vpl.count = 16;
    h.state_mut().session.technique = "unshadowed".into();
    h.state_mut().session.indirect.technique = Some("val".into());
    h.run_steps(3);
    h.state_mut().chrome.layout.focus(Pane::Explain);
    h.run_steps(1);
    let param = |h: &Harness<'static, ShadowLabApp>, key: &str, name: &str| {
        h.state().session.indirect.params.get(key).and_then(|p| p.get(name)).cloned()
    };
    // VALs: one VAL's contribution alone, then every VAL again.
    h.get_by_label("4. One VAL's soft shadow").click();
    h.run_steps(2);
    assert_eq!(param(&h, "val", "solo"), Some(ParamValue::Int(0)));
    h.get_by_label("5. Every VAL: the indirect light").click();
    h.run_steps(2);
    assert_eq!(param(&h, "val", "solo"), Some(ParamValue::Int(-1)), "back to every VAL");
    // Fuzzy clustering: each clustering alone (the paper's ablations), hard visibility, then the panel's choices.
    h.state_mut().session.indirect.technique = Some("fuzzy".into());
    h.state_mut().chrome.layout.focus(Pane::Explain);
    h.run_steps(3);
    let choice = |v: &str| Some(ParamValue::Choice(v.to_string()));
    h.get_by_label("2. VPL clusters").click();
    h.run_steps(2);
    assert_eq!(param(&h, "fuzzy", "cluster"), choice("vpl"));
    h.get_by_label("3-4. Shading-point clusters").click();
    h.run_steps(2);
    assert_eq!(param(&h, "fuzzy", "cluster"), choice("sp"));
    h.get_by_label("5. Visibility between representatives").click();
    h.run_steps(2);
    assert_eq!((param(&h, "fuzzy", "cluster"), param(&h, "fuzzy", "mode")), (choice("both"), choice("hard")));
    h.get_by_label("6. Weighted visibility").click();
    h.run_steps(2);
    assert_eq!((param(&h, "fuzzy", "cluster"), param(&h, "fuzzy", "mode")), (choice("both"), choice("weighted")));
}

#[test]
fn an_insm_viewpoint_under_the_pointer_has_a_tooltip() {
    let mut h = start("viewpoint-tooltip", "arcade");
    h.state_mut().session.technique = "insm".into();
    // The paper's cameras on the bounding box, inside the default view (the default distance puts them outside).
    let params = h.state_mut().session.params.entry("insm".into()).or_default();
    params.insert("box_distance".into(), shadowlab_core::technique::ParamValue::Float(1.0));
    h.run_steps(4);
    let p = projection(&h);
    let rect = h.state().views.last_viewport_rect.unwrap().shrink(70.0);
    let cameras =
        h.state_mut().views.gpu.as_mut().unwrap().main.technique("insm").unwrap().cameras_in_use("viewpoints");
    let pos = cameras
        .iter()
        .filter_map(|c| p.to_screen(c.position))
        .find(|s| rect.contains(*s))
        .expect("a viewpoint is on screen");
    let lines = h.state_mut().camera_tooltip(&p, pos);
    assert!(lines.len() == 3 && lines[0].contains(&format!("of {}", cameras.len())), "{lines:?}");
    assert!(lines[2].starts_with("looking at"), "{lines:?}");
    assert!(h.state_mut().camera_tooltip(&p, egui::pos2(-100.0, -100.0)).is_empty());
}

/// Where a hover point of `layer` of the indirect technique `key` is on screen, inside the view, with its index.
fn indirect_point_on_screen(h: &mut Harness<'static, ShadowLabApp>, key: &str, layer: &str) -> (egui::Pos2, usize) {
    let p = projection(h);
    let rect = h.state().views.last_viewport_rect.unwrap().shrink(20.0);
    let technique = h.state_mut().views.gpu.as_mut().unwrap().main.indirect_technique(key).unwrap();
    let points = technique.borrow().hover_points();
    points
        .iter()
        .filter(|q| q.layer == layer)
        .find_map(|q| p.to_screen(q.position).filter(|s| rect.contains(*s)).map(|s| (s, q.index)))
        .unwrap_or_else(|| panic!("no point of '{layer}' on screen"))
}

#[test]
fn vals_vpls_and_fuzzy_clusters_under_the_pointer_have_tooltips() {
    let mut h = start("overlay-tooltips", "cornell");
    h.state_mut().session.technique = "unshadowed".into();
    h.state_mut().session.indirect.vpl.count = 64;
    h.state_mut().session.indirect.technique = Some("val".into());
    h.run_steps(6);
    let p = projection(&h);
    // A VAL's centre: its number, VPL count, rectangle.
    let (at, k) = indirect_point_on_screen(&mut h, "val", "val centres");
    let lines = h.state_mut().overlay_tooltip(&p, at);
    assert!(lines[0].starts_with(&format!("VAL {k} (")) && lines[1].contains("VPLs"), "{lines:?}");
    // ... and where its map stands (its mean, or a member VPL for a small VAL).
    assert!(lines.last().unwrap().starts_with("map at "), "{lines:?}");
    // ... and how far its VPLs' normals spread (the cone a pixel's skip test uses).
    assert!(lines.iter().any(|l| l.starts_with("normal (") && l.contains("VPL normals")), "{lines:?}");
    // With the centres hidden, a VPL: its light and its VAL; with its layer hidden too, nothing.
    h.state_mut().session.view.overlays.insert("val centres".into(), false);
    let (at, i) = indirect_point_on_screen(&mut h, "val", "vpls by val");
    let lines = h.state_mut().overlay_tooltip(&p, at);
    assert!(lines[0].starts_with(&format!("VPL {i} of ")) && lines.last().unwrap().starts_with("in VAL "), "{lines:?}");
    h.state_mut().session.view.overlays.insert("vpls by val".into(), false);
    assert!(h.state_mut().overlay_tooltip(&p, at).is_empty(), "a hidden layer has no tooltips");
    // Fuzzy clustering: a VPL cluster's representative.
    h.state_mut().session.indirect.technique = Some("fuzzy".into());
    h.run_steps(6);
    let (at, k) = indirect_point_on_screen(&mut h, "fuzzy", "vpl cluster representatives");
    let lines = h.state_mut().overlay_tooltip(&p, at);
    assert!(lines[0].starts_with(&format!("VPL cluster {k} (")) && lines[1].ends_with("members"), "{lines:?}");
    // A pixel of the per-pixel shading-point cluster map, once that layer is on: its cluster.
    let centre = h.state().views.last_viewport_rect.unwrap().center();
    for layer in [
        "vpl cluster representatives",
        "vpls by cluster",
        "probe: clusters and visibility rays (green visible, red blocked)",
    ] {
        h.state_mut().session.view.overlays.insert(layer.into(), false);
    }
    assert!(h.state_mut().overlay_tooltip(&p, centre).is_empty(), "the map's layer is off");
    h.state_mut().session.view.overlays.insert("shading-point clusters".into(), true);
    let lines = h.state_mut().overlay_tooltip(&p, centre);
    let id: usize = lines
        .first()
        .and_then(|l| l.strip_prefix("shading-point clusters: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{lines:?}"));
    assert!(
        lines[1].starts_with(&format!("shading-point cluster {id} (")) && lines[2].ends_with("members"),
        "{lines:?}"
    );
}

#[test]
fn the_difference_is_computed_off_the_ui_thread_when_not_synchronous() {
    // Metrics with FLIP run on a worker: UI frames keep coming while it works, and its result arrives.
    use shadowlab::gui::document::ViewMode;
    let mut h =
        harness(Startup { data_dir: Some(data_dir("difference-async")), synchronous: false, ..Default::default() });
    h.state_mut().load_builtin("cornell");
    h.state_mut().session.view.mode = ViewMode::Difference;
    let start = std::time::Instant::now();
    while h.state().views.difference.is_none() && start.elapsed() < std::time::Duration::from_secs(120) {
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let d = h.state().views.difference.as_ref().expect("the worker's difference arrived");
    assert_eq!(d.metrics.rmse, 0.0, "the reference against itself");
}

#[test]
fn a_lost_device_saves_a_recovery_file_and_says_how_to_go_on() {
    // Destroying the device is what a driver reset does to it: the app stops rendering, saves the whole state
    // to recovery.ron, says so in the view, and (the binary; here only recorded) restarts on that file.
    let dir = data_dir("device-lost");
    let mut h = harness(Startup { data_dir: Some(dir.clone()), synchronous: true, ..Default::default() });
    h.state_mut().load_builtin("cornell");
    h.state_mut().session.technique = "lightcluster".into();
    h.run_steps(3);
    let lights = h.state().session.lights.clone();
    let device = h.state().views.gpu.as_ref().unwrap().ctx.device.clone();
    device.destroy();
    // wgpu reports a destroyed device at the next poll once its queue is empty (a real loss at once).
    let _ = device.poll(wgpu::PollType::wait_indefinitely());
    h.run_steps(3);
    let app = h.state();
    let recovery = app.recovery.clone().expect("the loss was handled");
    assert!(recovery.reason.contains("Destroyed"), "{}", recovery.reason);
    assert!(app.views.gpu.is_none(), "nothing renders with the lost device");
    let file = recovery.file.expect("the state was saved");
    assert_eq!(file, dir.join("recovery.ron"));
    let (program, args) = recovery.relaunch.expect("the command that goes on");
    assert!(program.file_name().is_some() && args == [file.display().to_string()], "{program:?} {args:?}");
    assert!(h.query_all_by_label_contains("The GPU device was lost").count() >= 1, "the window says so");
    // The recovery file brings everything back in a fresh app.
    let mut fresh = harness(Startup {
        data_dir: Some(data_dir("device-lost-fresh")),
        synchronous: true,
        path: Some(file),
        ..Default::default()
    });
    fresh.run_steps(3);
    assert_eq!(fresh.state().session.technique, "lightcluster");
    assert_eq!(fresh.state().session.lights, lights);
}

#[test]
fn auto_exposure_is_on_in_the_app_and_the_preview_holds_it() {
    let mut h = start("auto-exposure", "cornell");
    let settings = h.state().session.render_settings(egui::vec2(320.0, 200.0), false);
    assert_eq!(settings.auto_exposure, shadowlab_core::AutoExposure::Meter, "the full image meters");
    let preview = h.state().session.render_settings(egui::vec2(320.0, 200.0), true);
    assert_eq!(preview.auto_exposure, shadowlab_core::AutoExposure::Hold, "the preview holds the metered value");
    let metered = h.state().views.gpu.as_ref().unwrap().main.renderer.auto_exposure().unwrap();
    let (scale, average) = metered.expect("metered");
    assert!(scale.is_finite() && scale > 0.0 && average > 0.0, "{scale} {average}");
    // Side by side, the reference is shown at the technique's exposure (held, not metered on its own image).
    h.state_mut().session.technique = "lightcluster".into();
    h.state_mut().session.view.mode = shadowlab::gui::document::ViewMode::SideBySide;
    h.run_steps(6);
    let gpu = h.state().views.gpu.as_ref().unwrap();
    let main = gpu.main.renderer.auto_exposure().unwrap().unwrap();
    let reference = gpu.reference.renderer.auto_exposure().unwrap().unwrap();
    assert_eq!(gpu.reference.renderer.settings().auto_exposure, shadowlab_core::AutoExposure::Hold);
    assert_eq!(main.0, reference.0, "one exposure for both views");
    assert_eq!(h.state().views.metered_exposure.map(|m| m.0), Some(main.0), "the Render panel's figure is the view's");
    h.state_mut().session.view.auto_exposure = false;
    h.run_steps(3);
    assert_eq!(
        h.state().views.gpu.as_ref().unwrap().main.renderer.auto_exposure().unwrap(),
        None,
        "off: the exposure as set"
    );
}

#[test]
fn the_app_starts_on_a_stated_comparison_and_says_it_at_exit() {
    use shadowlab_core::technique::ParamValue;
    let mut h = started(
        "start-state",
        Some("cornell"),
        StartState {
            technique: Some("lightcluster".into()),
            params: vec!["d_init=0.9".into(), "filter=pcss".into()],
            view: Some("difference".into()),
            against: Some("raytraced".into()),
            against_params: vec!["bias=0.02".into()],
            ..Default::default()
        },
    );
    h.run_steps(6);
    let s = &h.state().session;
    assert_eq!(s.technique, "lightcluster");
    assert_eq!(s.params["lightcluster"]["d_init"], ParamValue::Float(0.9));
    assert_eq!(s.params["lightcluster"]["filter"], ParamValue::Choice("pcss".into()));
    assert_eq!(s.view.compare_against, "raytraced");
    assert_eq!(s.params["raytraced"]["bias"], ParamValue::Float(0.02));
    let line = h.state().exit_line();
    assert!(line.contains("view=difference | technique=lightcluster"), "{line}");
    assert!(line.contains("d_init=0.9") && line.contains("against=raytraced bias=0.02"), "{line}");
    assert!(line.contains(" rmse="), "the last metrics: {line}");
    // A parameter the technique lacks is a message, and the rest still applies.
    let mut bad = started(
        "start-state-bad",
        None,
        StartState {
            technique: Some("lightcluster".into()),
            params: vec!["warp=3".into()],
            against_indirect: Some("magic".into()),
            ..Default::default()
        },
    );
    bad.run_steps(2);
    assert_eq!(bad.state().session.technique, "lightcluster");
    bad.get_by_label_contains("has no parameter 'warp'");
    bad.get_by_label_contains("--app-against-indirect 'magic'");
}

#[test]
fn the_app_opens_on_an_explain_step_of_the_indirect_technique_and_refuses_a_step_it_lacks() {
    // A class opens the app on the VPL step: the selected light's RSM in the Shadow maps panel and in the view.
    let mut h = started(
        "start-explain",
        Some("cornell"),
        StartState {
            indirect: Some("vpl-raytraced".into()),
            explain: Some("vpl-raytraced:1".into()),
            ..Default::default()
        },
    );
    h.run_steps(6);
    let app = h.state();
    assert_eq!(app.chrome.explain.step, Some(("vpl-raytraced".into(), 0)));
    assert!(app.chrome.inspector.rsm_shown && app.chrome.explain.map_in_view);
    assert!(app.chrome.inspector.rsm.image.is_some(), "light 0's RSM was cast");
    // The direct technique's step by number; a step past the list and a technique not in use are messages.
    let mut h = started(
        "start-explain-bad",
        None,
        StartState { technique: Some("lightcluster".into()), explain: Some("9".into()), ..Default::default() },
    );
    h.run_steps(2);
    h.get_by_label_contains("--app-explain '9': 'lightcluster' has 6 Explain steps (1 to 6)");
    assert_eq!(h.state().chrome.explain.step, None);
    let mut h =
        started("start-explain-other", None, StartState { explain: Some("val:2".into()), ..Default::default() });
    h.run_steps(2);
    h.get_by_label_contains("'val' is not the technique or the indirect technique");
}

#[test]
fn the_app_starts_with_the_overlay_layers_it_is_told_and_names_the_ones_it_offers_for_a_bad_one() {
    // A README picture by command: INSM's mesh shown, the light ranges (shown by default over INSM) hidden.
    let mut h = started(
        "start-overlays",
        Some("cornell"),
        StartState {
            technique: Some("insm".into()),
            overlays: vec!["insm MESH (wireframe)".into(), "light ranges=off".into(), "no such layer".into()],
            ..Default::default()
        },
    );
    // INSM offers its mesh layers once it has a mesh: the names are checked after the first frame.
    h.run_steps(6);
    assert!(h.state().views.gpu.as_ref().unwrap().main.last_report.is_some(), "a frame completed");
    let layers: std::collections::BTreeMap<String, bool> = h.state_mut().overlay_layers().into_iter().collect();
    assert_eq!(layers.get("INSM mesh (wireframe)"), Some(&true), "{layers:?}");
    assert_eq!(layers.get("light ranges"), Some(&false), "{layers:?}");
    assert!(!h.state().session.view.overlays.contains_key("no such layer"));
    assert!(!h.state().session.view.overlays.contains_key("insm MESH (wireframe)"), "the offered name kept");
    h.get_by_label_contains("--app-overlay 'no such layer': no such layer (the technique offers: ");
}

/// Click "Run trade-off" (scrolled into the Sweep pane) and wait for the worker to finish.
fn run_tradeoff(h: &mut Harness<'static, ShadowLabApp>) {
    h.get_by_label("Run trade-off").scroll_to_me();
    h.run_steps(2);
    h.get_by_label("Run trade-off").click_accesskit();
    h.run_steps(2);
    assert!(h.state().views.tradeoff.is_some(), "the trade-off started");
    let started = std::time::Instant::now();
    while h.state_mut().views.tradeoff.as_mut().is_some_and(|t| t.poll()) {
        assert!(started.elapsed().as_secs() < 120, "the trade-off finishes");
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.step();
    }
}

#[test]
fn the_tradeoff_panel_runs_on_a_worker_and_tunes_the_view_to_its_pick() {
    use shadowlab::gui::tradeoff_input::{ParamRange, TryInput};
    use shadowlab_core::technique::ParamValue;
    // A window tall enough for the plot to be scrolled into the Sweep pane.
    let startup = Startup { data_dir: Some(data_dir("tradeoff")), synchronous: true, ..Default::default() };
    let mut h = harness_sized(startup, (1200.0, 900.0));
    h.state_mut().load_builtin("cornell");
    h.run_steps(3);
    h.state_mut().chrome.layout.focus(Pane::Sweep);
    h.run_steps(2);
    {
        let input = &mut h.state_mut().chrome.tradeoff_input;
        let d_init = ParamRange { key: "d_init".into(), from: 0.2, to: 1.6, count: 8 };
        input.tries.insert("lightcluster".into(), TryInput { on: true, params: vec![d_init] });
        input.tries.insert("reference".into(), TryInput::default());
        input.use_budget = true;
        input.budget_ms = 1e6;
    }
    run_tradeoff(&mut h);
    h.run_steps(2);
    let t = h.state().views.tradeoff.as_ref().expect("a trade-off ran");
    assert!(t.worker.error.is_none(), "{:?}", t.worker.error);
    // Every d_init fits a budget of 1e6 ms: the two ends tell so, and nothing else is rendered.
    assert_eq!(t.rows.len(), 2, "{:?}", t.rows);
    let pick = t.pick().expect("a pick within the budget");
    let (value, error) = (t.rows[pick].setting[0].1.clone(), t.rows[pick].error);
    assert!(t.rows.iter().all(|r| r.error >= error), "the pick has the lowest error");
    assert_eq!(h.state().session.technique, "reference");
    h.get_by_label("Tune: use the pick").click_accesskit();
    h.run_steps(2);
    let s = &h.state().session;
    assert_eq!(s.technique, "lightcluster", "Tune loads the pick's technique");
    assert_eq!(s.params["lightcluster"]["d_init"], ParamValue::Float(value.parse().unwrap()), "and its d_init");

    // Within an error instead: every configuration fits, the pick is the fastest.
    {
        let input = &mut h.state_mut().chrome.tradeoff_input;
        input.use_budget = false;
        input.use_max_error = true;
        input.max_error = 1e9;
    }
    run_tradeoff(&mut h);
    let t = h.state().views.tradeoff.as_ref().unwrap();
    assert!(matches!(t.goal, shadowlab::tradeoff::Goal::MaxError(_)), "{:?}", t.goal);
    let points = t.points();
    let pick = t.pick().expect("everything fits");
    assert!(points.iter().all(|p| p.ms >= points[pick].ms), "the fastest is picked");

    // Against a work count: the rows carry the frame's counts and the plot draws them on that axis.
    let key = t.work_keys().into_iter().find(|k| k == "depth_triangles").expect("a depth-triangle count");
    let rows: Vec<(String, f64)> = t.rows.iter().map(|r| (r.setting[0].1.clone(), r.work[&key])).collect();
    h.state_mut().chrome.tradeoff_input.x_axis = Some(key.clone());
    h.run_steps(2);
    // Clicking a point loads its configuration: the one that is not the view's now.
    let loaded = h.state().session.params["lightcluster"]["d_init"].clone();
    let i = rows.iter().position(|(v, _)| ParamValue::Float(v.parse().unwrap()) != loaded).expect("another row");
    // The view on another technique (the panel above the plot changes with it), then scroll the Sweep pane until the plot (below the section's inputs) is on screen.
    h.state_mut().session.technique = "reference".into();
    h.run_steps(3);
    let pane = h.state().chrome.layout.rect(Pane::Sweep).expect("the sweep pane is laid out");
    for _ in 0..20 {
        if h.state().chrome.tradeoff_input.drawn.iter().all(|p| pane.shrink(4.0).contains(*p)) {
            break;
        }
        move_to(&mut h, pane.center());
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, -40.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Wheel,
            modifiers: egui::Modifiers::NONE,
        });
        h.run_steps(2);
    }
    // Smooth scrolling settles, and the plot's bounds with it.
    h.run_steps(20);
    let drawn = h.state().chrome.tradeoff_input.drawn.clone();
    assert_eq!(drawn.len(), rows.len());
    assert!(drawn.iter().all(|p| pane.contains(*p)), "the plot is on screen: {drawn:?} in {pane:?}");
    assert!(
        drawn
            .iter()
            .zip(&rows)
            .all(|(a, b)| drawn.iter().zip(&rows).all(|(c, d)| (a.x < c.x) == (b.1 < d.1) || b.1 == d.1)),
        "points drawn in the order of their counts: {drawn:?} {rows:?}"
    );
    move_to(&mut h, drawn[i]);
    press(&mut h, drawn[i], true, egui::Modifiers::NONE);
    press(&mut h, drawn[i], false, egui::Modifiers::NONE);
    h.run_steps(2);
    let s = &h.state().session;
    assert_eq!(s.technique, "lightcluster", "a click on a point loads its technique");
    assert_eq!(s.params["lightcluster"]["d_init"], ParamValue::Float(rows[i].0.parse().unwrap()), "and its d_init");

    // Two parameters, a numeric one and a choice: every combination is rendered.
    {
        let input = &mut h.state_mut().chrome.tradeoff_input;
        input.use_max_error = false;
        let d_init = ParamRange { key: "d_init".into(), from: 0.4, to: 1.2, count: 2 };
        let filter = ParamRange { key: "filter".into(), from: 0.0, to: 1.0, count: 2 };
        input.tries.insert("lightcluster".into(), TryInput { on: true, params: vec![d_init, filter] });
    }
    run_tradeoff(&mut h);
    let t = h.state().views.tradeoff.as_ref().unwrap();
    let mut settings: Vec<String> = t.rows.iter().map(|r| shadowlab::tradeoff::setting_text(&r.setting)).collect();
    settings.sort();
    assert_eq!(
        settings,
        ["d_init=0.4 filter=pcf", "d_init=0.4 filter=pcss", "d_init=1.2 filter=pcf", "d_init=1.2 filter=pcss"],
        "{:?}",
        t.rows
    );
}

/// A small deterministic generator (xorshift64*), so a failing random run can be replayed from its seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn pos(&mut self) -> egui::Pos2 {
        egui::pos2(self.below(SIZE.0 as u64) as f32, self.below(SIZE.1 as u64) as f32)
    }
}

fn key(h: &mut Harness<'static, ShadowLabApp>, key: egui::Key, modifiers: egui::Modifiers) {
    for pressed in [true, false] {
        h.event(egui::Event::Key { key, physical_key: None, pressed, repeat: false, modifiers });
    }
}

/// Drive the whole app with `events` random events from `seed`: clicks and drags anywhere (menus, panels, the
/// view, the gizmo), keys with undo/redo and the shortcuts, technique, indirect and view switches, the wheel.
/// Nothing may panic, and undoing every edit brings the lights back to where they were when the history was
/// last empty (the start, or the last scene loaded).
fn random_use(seed: u64, events: usize) {
    use shadowlab::gui::document::{ViewMode, HISTORY_LIMIT};
    use shadowlab_core::technique::registry::{INDIRECT_REGISTRY, REGISTRY};
    let mut h = harness(Startup {
        data_dir: Some(data_dir(&format!("random-{seed}"))),
        builtin: Some("cornell".into()),
        no_file_dialogs: true,
        ..Default::default()
    });
    h.state_mut().session.indirect.vpl.count = 32;
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut baseline = h.state().session.lights.clone();
    let mut overflowed = false;
    let (ctrl, shift) = (egui::Modifiers::COMMAND, egui::Modifiers::SHIFT);
    let keys = [
        (egui::Key::Z, ctrl),
        (egui::Key::Z, ctrl | shift),
        (egui::Key::Y, ctrl),
        (egui::Key::Delete, egui::Modifiers::NONE),
        (egui::Key::D, ctrl),
        (egui::Key::F, egui::Modifiers::NONE),
        (egui::Key::Tab, egui::Modifiers::NONE),
        (egui::Key::Escape, egui::Modifiers::NONE),
        (egui::Key::W, egui::Modifiers::NONE),
        (egui::Key::S, egui::Modifiers::NONE),
        (egui::Key::F12, egui::Modifiers::NONE),
    ];
    for _ in 0..events {
        match rng.below(100) {
            0..=34 => {
                let (at, modifiers) = (rng.pos(), if rng.below(10) == 0 { ctrl } else { egui::Modifiers::NONE });
                move_to(&mut h, at);
                press(&mut h, at, true, modifiers);
                press(&mut h, at, false, modifiers);
            }
            35..=54 => {
                let mut at = rng.pos();
                move_to(&mut h, at);
                press(&mut h, at, true, egui::Modifiers::NONE);
                for _ in 0..3 {
                    at += egui::vec2(rng.below(61) as f32 - 30.0, rng.below(61) as f32 - 30.0);
                    move_to(&mut h, at);
                }
                press(&mut h, at, false, egui::Modifiers::NONE);
            }
            55..=69 => {
                let (k, m) = keys[rng.below(keys.len() as u64) as usize];
                key(&mut h, k, m);
            }
            70..=79 => {
                let entry = &REGISTRY[rng.below(REGISTRY.len() as u64) as usize];
                h.state_mut().session.technique = entry.key.to_string();
            }
            80..=84 => {
                let i = rng.below(INDIRECT_REGISTRY.len() as u64 + 1) as usize;
                h.state_mut().session.indirect.technique = INDIRECT_REGISTRY.get(i).map(|e| e.key.to_string());
            }
            85..=89 => {
                let modes = [ViewMode::Single, ViewMode::SideBySide, ViewMode::Split, ViewMode::Difference];
                h.state_mut().session.view.mode = modes[rng.below(4) as usize];
            }
            90..=94 => move_to(&mut h, rng.pos()),
            _ => {
                let at = rng.pos();
                move_to(&mut h, at);
                let delta = egui::vec2(0.0, rng.below(200) as f32 - 100.0);
                h.event(egui::Event::MouseWheel {
                    unit: egui::MouseWheelUnit::Point,
                    delta,
                    phase: egui::TouchPhase::Move,
                    source: egui::MouseWheelSource::Unknown,
                    modifiers: Default::default(),
                });
            }
        }
        h.step();
        let s = &h.state().session;
        if s.history.depth() == 0 {
            baseline = s.lights.clone();
        }
        overflowed |= s.history.depth() >= HISTORY_LIMIT;
    }
    h.run_steps(2);
    while h.state().session.history.can_undo() {
        h.state_mut().session.undo();
    }
    if overflowed {
        eprintln!("random use (seed {seed}): the history overflowed; undo-all not checked");
    } else {
        assert_eq!(h.state().session.lights, baseline, "seed {seed}: undoing everything restores the lights");
    }
}

#[test]
fn the_app_survives_random_use_and_undo_restores_the_lights() {
    // Short in CI; SHADOWLAB_RANDOM_EVENTS=5000 (and SHADOWLAB_RANDOM_SEED) for a long run.
    let events = std::env::var("SHADOWLAB_RANDOM_EVENTS").ok().and_then(|v| v.parse().ok()).unwrap_or(150);
    let seed = std::env::var("SHADOWLAB_RANDOM_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(7);
    random_use(seed, events);
}

#[test]
fn suns_are_added_aimed_undone_and_saved_in_the_scene_file() {
    // Issue 25: the Lights panel adds a directional light, the views shade it, undo removes it, and a scene
    // file keeps it.
    let dir = data_dir("suns");
    let mut h = start("suns", "cornell");
    assert!(h.state().session.suns.is_empty(), "the built-in Cornell box has no sun");
    let mean = |h: &Harness<'static, ShadowLabApp>| {
        let gpu = h.state().views.gpu.as_ref().unwrap();
        let hdr = gpu.main.renderer.read_hdr().unwrap();
        hdr.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / hdr.len() as f64
    };
    let passes = |h: &Harness<'static, ShadowLabApp>| {
        let gpu = h.state().views.gpu.as_ref().unwrap();
        gpu.main
            .last_report
            .as_ref()
            .expect("a complete frame")
            .passes
            .iter()
            .map(|p| p.name.clone())
            .collect::<Vec<_>>()
    };
    let unlit = mean(&h);
    assert!(!passes(&h).iter().any(|p| p.contains("directional")));

    h.state_mut().chrome.layout.focus(Pane::Lights);
    h.run_steps(2);
    let add = h.get_by_label("+ sun");
    add.scroll_to_me();
    add.click_accesskit();
    h.run_steps(4);
    let suns = h.state().session.suns.clone();
    assert_eq!(suns.len(), 1, "the button added a sun");
    let (_, elevation) = shadowlab::gui::panels::lights::sun_angles(suns[0].direction);
    assert!((elevation - 50.0).abs() < 1e-3, "{elevation}");
    // From behind the viewer: it shines the way the camera looks.
    assert!(suns[0].direction.dot(h.state().session.camera.camera().forward()) > 0.3, "{:?}", suns[0].direction);
    assert!(passes(&h).iter().any(|p| p.contains("directional")), "the sun is shaded: {:?}", passes(&h));
    // The sun through the box's open front lights its floor.
    let lit = mean(&h);
    assert!(lit > unlit * 1.001, "the sun adds light: {unlit} -> {lit}");
    assert!(h.query_all_by_label_contains("azimuth").count() >= 1, "the sun's angles are edited in the panel");
    // Its arrow is a layer of the view, on by default, drawn with its legend.
    assert!(h.state_mut().overlay_layers().iter().any(|(name, on)| name == "suns" && *on), "no suns layer");
    assert!(h.state().views.legends.iter().any(|(n, _)| n == "suns"), "the suns layer is not drawn");

    // Saved and loaded in a fresh app with the scene.
    let file = dir.join("sunny.ron");
    h.state_mut().save_scene_file(&file).unwrap();
    let mut fresh = reopen(&file, &dir);
    fresh.run_steps(3);
    assert_eq!(fresh.state().session.suns, suns, "the scene file keeps the sun");

    // Undo removes it, redo brings it back.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    assert!(h.state().session.suns.is_empty(), "Ctrl+Z removes the sun");
    assert!(!h.state_mut().overlay_layers().iter().any(|(name, _)| name == "suns"), "a suns layer without suns");
    assert!(!passes(&h).iter().any(|p| p.contains("directional")), "{:?}", passes(&h));
    h.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    h.run_steps(3);
    assert_eq!(h.state().session.suns, suns, "Ctrl+Shift+Z adds it again");
}
