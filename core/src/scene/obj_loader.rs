//! OBJ + MTL loading with `tobj`.
//!
//! Geometry is parsed by `tobj` (triangulated, one index per vertex). MTL files are parsed here rather than
//! by `tobj` because its MTL parser panics on one-value colours (`Kd 0.5`, valid MTL) and keeps trailing
//! `# comments` in texture names; the materials are handed back to `tobj` so `usemtl` resolves as usual.
//!
//! Conventions:
//! - MTL colours (`Kd`, `Ke`, `Ks`) are taken as linear RGB; `map_Kd` is an sRGB texture that the renderer
//!   multiplies by `Kd` (as the MTL spec says), `d` is the alpha.
//! - OBJ texture coordinates have their origin at the bottom left; they are flipped to the top-left origin of
//!   the rest of the renderer (glTF, wgpu): `v' = 1 - v`.
//! - Missing MTL files and textures are warnings (in `Scene::warnings` and the log), never errors.

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::texture::{decode_parallel, find_file_case_insensitive, load_texture};
use super::{Aabb, Camera, Material, Mesh, Scene, SceneSource};
use crate::error::LoadError;

/// Load an OBJ file (triangulated), its MTL (`Kd`, `map_Kd`, `Ke`, `Ks`, `Ns`, `d`) and textures.
/// Positions are multiplied by `unit_scale`. OBJ files have no lights; the camera frames the scene.
pub fn load_obj(path: &Path, unit_scale: f32) -> Result<Scene, LoadError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut warnings = Vec::new();
    let (models, mtl_materials) = read_and_parse(path, dir, &mut warnings)?;

    let mut scene = Scene {
        name: path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "obj".into()),
        source: SceneSource::File { path: path.to_path_buf(), unit_scale },
        meshes: Vec::with_capacity(models.len()),
        materials: Vec::with_capacity(mtl_materials.len() + 1),
        textures: Vec::new(),
        lights: Vec::new(),
        directional: Vec::new(),
        camera: Camera::framing(&Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) }),
        bounds: Aabb::EMPTY,
        warnings,
    };
    convert_materials(&mtl_materials, dir, &mut scene);

    let mut default_material = None;
    for model in models {
        let tobj::Model { mesh, name } = model;
        let vertex_count = mesh.positions.len() / 3;
        if mesh.indices.is_empty() || vertex_count == 0 {
            continue;
        }
        let positions: Vec<Vec3> =
            mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2]) * unit_scale).collect();
        // With single_index, tobj pushes a normal / texcoord only for vertices that have one; a partial set
        // cannot be matched to vertices any more, so it is dropped (normals are then regenerated).
        let normals = if mesh.normals.len() == vertex_count * 3 {
            mesh.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])).collect()
        } else {
            if !mesh.normals.is_empty() {
                warn(
                    &mut scene.warnings,
                    format!("object '{name}': some vertices have no normal; normals regenerated"),
                );
            }
            Vec::new()
        };
        let uvs = if mesh.texcoords.len() == vertex_count * 2 {
            mesh.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect()
        } else {
            if !mesh.texcoords.is_empty() {
                warn(&mut scene.warnings, format!("object '{name}': some vertices have no texture coordinates"));
            }
            Vec::new()
        };
        let material = match mesh.material_id {
            Some(id) if id < mtl_materials.len() => id,
            _ => *default_material.get_or_insert_with(|| {
                scene.materials.push(Material::default());
                scene.materials.len() - 1
            }),
        };
        scene.meshes.push(Mesh { name, positions, normals, uvs, uvs1: Vec::new(), indices: mesh.indices, material });
    }

    scene.finalize(path)?;
    scene.camera = Camera::framing(&scene.bounds);
    Ok(scene)
}

/// Read the file and parse it; the file's bytes are freed on return.
fn read_and_parse(
    path: &Path,
    dir: &Path,
    warnings: &mut Vec<String>,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>), LoadError> {
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => LoadError::NotFound { path: path.to_path_buf() },
        _ => LoadError::Io { path: path.to_path_buf(), source },
    })?;
    let obj_error = |reason: String| LoadError::Obj { path: path.to_path_buf(), reason };
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(obj_error("the file is empty".into()));
    }
    // OBJ is text; NUL bytes mean a binary file (or a corrupted download), which tobj would happily skip
    // line by line and report as "no triangles".
    if bytes.contains(&0) {
        return Err(obj_error("this is not a text OBJ file (it contains binary data)".into()));
    }
    // Real files carry Latin-1 names and comments; a lossy conversion keeps them readable instead of failing.
    let text = String::from_utf8_lossy(&bytes);
    parse_obj(&text, dir, warnings).map_err(obj_error)
}

/// Parse the OBJ text with tobj, loading MTL files (found case-insensitively next to the OBJ) on the way.
/// Returns a readable reason on failure.
fn parse_obj(
    text: &str,
    dir: &Path,
    warnings: &mut Vec<String>,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>), String> {
    // The update is needed when tobj's optional `merging`/`reordering` features add fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        // Without these, tobj turns `p` and `l` elements into degenerate triangles.
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // tobj resolves a negative (relative) index reaching before the first element to a huge index and then
    // does unchecked arithmetic on it (`vt * 2 + 1`), which overflows and panics in debug builds. Files with
    // relative texture/normal indices are rare and small, so check them up front (a fast substring search
    // keeps the common case free); the catch_unwind below stays as a backstop for anything else.
    if text.contains("/-") {
        if let Some(at) = locate_face_problem(text) {
            return Err(format!("face index out of range ({at})"));
        }
    }
    let mtl_warnings = RefCell::new(Vec::new());
    let material_loader = |mtl: &Path| load_mtl_lenient(dir, mtl, &mut mtl_warnings.borrow_mut());
    // User files must never take the program down, whatever tobj does with them.
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &options, material_loader)
    }));
    warnings.extend(mtl_warnings.into_inner());
    let (models, materials) = match result {
        Ok(Ok(loaded)) => loaded,
        Ok(Err(e)) => return Err(describe_tobj_error(text, e)),
        Err(_) => {
            return Err(match locate_face_problem(text) {
                Some(at) => format!("face index out of range ({at})"),
                None => "the OBJ parser failed on malformed data".into(),
            })
        }
    };
    // The loader above never returns an error, so a failed MTL cannot surface here; stay defensive anyway.
    let materials = materials.unwrap_or_else(|e| {
        warn(warnings, format!("cannot load materials: {e}"));
        Vec::new()
    });
    Ok((models, materials))
}

/// Resolve and parse an `mtllib` reference. A missing or unreadable MTL is a warning and yields no
/// materials (faces using them get the default material).
fn load_mtl_lenient(dir: &Path, mtl: &Path, warnings: &mut Vec<String>) -> tobj::MTLLoadResult {
    let reference = mtl.to_string_lossy();
    // `mtllib a.mtl b.mtl` names several libraries; names with spaces are also seen, so try the whole
    // string first.
    let candidates: Vec<&str> = if find_file_case_insensitive(dir, &reference).is_some() {
        vec![reference.as_ref()]
    } else {
        reference.split_whitespace().collect()
    };
    let mut materials = Vec::new();
    for name in candidates {
        let Some(file) = find_file_case_insensitive(dir, name) else {
            warn(
                warnings,
                format!("material library '{name}' not found in {}; using default materials", dir.display()),
            );
            continue;
        };
        match std::fs::read(&file) {
            Ok(bytes) => {
                let label = file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                materials.extend(parse_mtl(&String::from_utf8_lossy(&bytes), &label, warnings));
            }
            Err(e) => warn(warnings, format!("cannot read material library {}: {e}", file.display())),
        }
    }
    let names = materials.iter().enumerate().map(|(i, m): (usize, &tobj::Material)| (m.name.clone(), i)).collect();
    Ok((materials, names))
}

/// A lenient MTL parser: unknown statements are kept in `unknown_param`, unparsable values are warnings.
fn parse_mtl(text: &str, label: &str, warnings: &mut Vec<String>) -> Vec<tobj::Material> {
    let mut materials: Vec<tobj::Material> = Vec::new();
    for (number, raw) in text.lines().enumerate() {
        let line = strip_comment(raw).trim();
        if line.is_empty() {
            continue;
        }
        let (keyword, rest) = split_token(line);
        let keyword = keyword.to_ascii_lowercase();
        if keyword == "newmtl" {
            let name = if rest.is_empty() { format!("unnamed_{}", number + 1) } else { rest.to_string() };
            materials.push(tobj::Material { name, ..Default::default() });
            continue;
        }
        // Statements before the first `newmtl` belong to no material.
        let Some(m) = materials.last_mut() else { continue };
        let mut bad_value = || warn(warnings, format!("{label}:{}: cannot parse '{line}'", number + 1));
        match keyword.as_str() {
            "kd" | "ka" | "ks" | "ke" => match parse_color(rest) {
                Some(c) => match keyword.as_str() {
                    "kd" => m.diffuse = Some(c),
                    "ka" => m.ambient = Some(c),
                    "ks" => m.specular = Some(c),
                    _ => m.emissive = Some(c),
                },
                None => bad_value(),
            },
            "ns" | "d" | "ni" => match rest.split_whitespace().next().and_then(|v| v.parse::<f32>().ok()) {
                Some(v) if v.is_finite() => match keyword.as_str() {
                    "ns" => m.shininess = Some(v),
                    "d" => m.dissolve = Some(v),
                    _ => m.optical_density = Some(v),
                },
                _ => bad_value(),
            },
            "illum" => match rest.split_whitespace().next().and_then(|v| v.parse::<u8>().ok()) {
                Some(v) => m.illumination_model = Some(v),
                None => bad_value(),
            },
            "map_kd" => match texture_file_name(rest) {
                Some(name) => m.diffuse_texture = Some(name.to_string()),
                None => bad_value(),
            },
            _ => {
                m.unknown_param.insert(keyword, rest.to_string());
            }
        }
    }
    materials
}

/// Cut a trailing `# comment` (a `#` at the start or after whitespace, so `tex#1.png` survives).
fn strip_comment(line: &str) -> &str {
    let bytes = line.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'#' && (i == 0 || bytes[i - 1].is_ascii_whitespace()) {
            return &line[..i];
        }
    }
    line
}

/// Split off the first whitespace-separated token; the remainder is trimmed.
fn split_token(s: &str) -> (&str, &str) {
    let s = s.trim_start();
    match s.find(char::is_whitespace) {
        Some(i) => (&s[..i], s[i..].trim()),
        None => (s, ""),
    }
}

/// `r g b`, or a single `r` meaning grey (MTL allows omitting g and b). `spectral`/`xyz` forms are rejected.
fn parse_color(s: &str) -> Option<[f32; 3]> {
    let values: Vec<f32> = s.split_whitespace().take(3).map(|v| v.parse::<f32>()).collect::<Result<_, _>>().ok()?;
    let c = match values[..] {
        [r] => [r, r, r],
        [r, g, b] => [r, g, b],
        _ => return None,
    };
    c.iter().all(|v| v.is_finite()).then_some(c)
}

/// The file name of a `map_*` statement, skipping options such as `-bm 0.5`, `-s 1 1 1` or `-clamp on`.
fn texture_file_name(mut rest: &str) -> Option<&str> {
    loop {
        let (token, after) = split_token(rest);
        if !token.starts_with('-') || token.len() < 2 || token[1..].parse::<f32>().is_ok() || after.is_empty() {
            break;
        }
        // Number of arguments each option takes (`o`, `s`, `t` take 1 to 3 numbers).
        let max_args = match token {
            "-o" | "-s" | "-t" => 3,
            "-mm" => 2,
            _ => 1,
        };
        rest = after;
        for i in 0..max_args {
            let (arg, after_arg) = split_token(rest);
            // The last token is always the file name. Only the first argument may be a word (`on`, `off`, `r`,
            // `cube_top`, ...); further ones are optional numbers.
            if after_arg.is_empty() || (i > 0 && arg.parse::<f32>().is_err()) {
                break;
            }
            rest = after_arg;
        }
    }
    let name = rest.trim().trim_matches('"');
    (!name.is_empty()).then_some(name)
}

/// Turn the MTL materials into scene materials, loading each distinct texture file once.
fn convert_materials(mtl: &[tobj::Material], dir: &Path, scene: &mut Scene) {
    // Resolve texture names to files first, so that duplicates (same file under different spellings) are
    // decoded once, and in parallel.
    let mut files: Vec<PathBuf> = Vec::new();
    let mut file_index: HashMap<PathBuf, usize> = HashMap::new();
    let mut material_file: Vec<Option<usize>> = Vec::with_capacity(mtl.len());
    let mut missing_warned: HashSet<&str> = HashSet::new();
    for m in mtl {
        let file = m.diffuse_texture.as_deref().and_then(|name| {
            let found = find_file_case_insensitive(dir, name);
            if found.is_none() && missing_warned.insert(name) {
                warn(
                    &mut scene.warnings,
                    format!("missing texture '{name}' (material '{}'), looked in {}", m.name, dir.display()),
                );
            }
            let found = found?;
            let key = found.canonicalize().unwrap_or_else(|_| found.clone());
            Some(*file_index.entry(key).or_insert_with(|| {
                files.push(found);
                files.len() - 1
            }))
        });
        material_file.push(file);
    }

    let decoded = decode_parallel(&files, |file| load_texture(file));
    let mut texture_of_file = Vec::with_capacity(files.len());
    for result in decoded {
        match result {
            Ok(texture) => {
                scene.textures.push(texture);
                texture_of_file.push(Some(scene.textures.len() - 1));
            }
            Err(e) => {
                warn(&mut scene.warnings, format!("cannot load texture: {e}"));
                texture_of_file.push(None);
            }
        }
    }

    for (m, file) in mtl.iter().zip(material_file) {
        let kd = m.diffuse.map_or(Vec3::splat(0.8), Vec3::from);
        let alpha = m.dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
        // illum 0 and 1 are the MTL models without highlights.
        let specular = match m.illumination_model {
            Some(0 | 1) => Vec3::ZERO,
            _ => m.specular.map_or(Vec3::ZERO, Vec3::from).max(Vec3::ZERO),
        };
        scene.materials.push(Material {
            name: m.name.clone(),
            base_color: Vec4::from((kd.max(Vec3::ZERO), alpha)),
            base_color_texture: file.and_then(|f| texture_of_file[f]),
            emissive: m.emissive.map_or(Vec3::ZERO, Vec3::from).max(Vec3::ZERO),
            emissive_texture: None,
            occlusion_texture: None,
            specular,
            shininess: m.shininess.filter(|s| *s > 0.0).unwrap_or(Material::default().shininess),
            // Sponza's MTL expects its leaves' texture alpha to cut them out.
            alpha_cutoff: 0.5,
            ..Material::default()
        });
    }
}

/// Turn a tobj error into a message, pointing at the offending line when it can be found.
fn describe_tobj_error(text: &str, error: tobj::LoadError) -> String {
    use tobj::LoadError as E;
    let location = match error {
        E::PositionParseError | E::ScalingByZeroError | E::ColorParseError => {
            locate_line(text, |kw, rest| kw == "v" && !valid_position(rest))
        }
        E::NormalParseError => locate_line(text, |kw, rest| kw == "vn" && !floats_ok(rest, 3)),
        E::TexcoordParseError => locate_line(text, |kw, rest| kw == "vt" && !floats_ok(rest, 2)),
        E::MaterialParseError => locate_line(text, |kw, rest| kw == "usemtl" && rest.is_empty()),
        E::FaceParseError
        | E::FaceVertexOutOfBounds
        | E::FaceTexCoordOutOfBounds
        | E::FaceNormalOutOfBounds
        | E::FaceColorOutOfBounds
        | E::InvalidPolygon => locate_face_problem(text),
        _ => None,
    };
    match location {
        Some(at) => format!("{error} ({at})"),
        None => error.to_string(),
    }
}

fn floats_ok(rest: &str, n: usize) -> bool {
    let values: Vec<&str> = rest.split_whitespace().take(n).collect();
    values.len() == n && values.iter().all(|v| v.parse::<f32>().is_ok())
}

/// tobj accepts `x y z`, `x y z w` (w != 0) and `x y z r g b`.
fn valid_position(rest: &str) -> bool {
    let values: Vec<Option<f32>> = rest.split_whitespace().map(|v| v.parse::<f32>().ok()).collect();
    values.iter().take(3).all(Option::is_some)
        && match values.len() {
            3 | 6 => true,
            4 => values[3].is_some_and(|w| w != 0.0),
            _ => false,
        }
}

/// The first line (1-based) whose keyword and arguments satisfy `is_bad`, as "line N: `text`".
fn locate_line(text: &str, is_bad: impl Fn(&str, &str) -> bool) -> Option<String> {
    text.lines().enumerate().find_map(|(i, line)| {
        let (kw, rest) = split_token(line);
        is_bad(kw, rest).then(|| describe_line(i, line))
    })
}

fn describe_line(index: usize, line: &str) -> String {
    let line = line.trim();
    let shown: Cow<str> = if line.chars().count() > 80 {
        format!("{}...", line.chars().take(80).collect::<String>()).into()
    } else {
        line.into()
    };
    format!("line {}: `{shown}`", index + 1)
}

/// Find the first face whose indices do not parse or point outside the vertex data, judged as tobj does:
/// positive indices against the whole file's data (faces are resolved at the end), negative ones relative
/// to the data read so far, and texture/normal indices not at all when the file has no `vt`/`vn`.
fn locate_face_problem(text: &str) -> Option<String> {
    let (mut v_total, mut vt_total, mut vn_total) = (0i64, 0i64, 0i64);
    for line in text.lines() {
        match split_token(line).0 {
            "v" => v_total += 1,
            "vt" => vt_total += 1,
            "vn" => vn_total += 1,
            _ => {}
        }
    }
    let (mut v_seen, mut vt_seen, mut vn_seen) = (0i64, 0i64, 0i64);
    for (i, line) in text.lines().enumerate() {
        let (kw, rest) = split_token(line);
        match kw {
            "v" => v_seen += 1,
            "vt" => vt_seen += 1,
            "vn" => vn_seen += 1,
            "f" => {
                let ok = rest.split_whitespace().all(|corner| {
                    corner.split('/').enumerate().all(|(k, part)| {
                        let (seen, total) = match k {
                            0 => (v_seen, v_total),
                            1 => (vt_seen, vt_total),
                            2 => (vn_seen, vn_total),
                            _ => return false,
                        };
                        if part.is_empty() || (k > 0 && total == 0) {
                            return k > 0;
                        }
                        match part.parse::<i64>() {
                            Ok(x) if x > 0 => x <= total,
                            Ok(x) if x < 0 => seen + x >= 0,
                            _ => false,
                        }
                    })
                });
                if !ok {
                    return Some(describe_line(i, line));
                }
            }
            _ => {}
        }
    }
    None
}

fn warn(warnings: &mut Vec<String>, message: String) {
    log::warn!("{message}");
    warnings.push(message);
}
