//! Every composed WGSL module (the shared ones and every registered technique's) validates with naga; every
//! `.wgsl` file of the repository is part of one; a technique's own WGSL lives in its folder; and outside its
//! folder and the registry no source file names a technique's module.

use std::path::{Path, PathBuf};

use shadowlab_core::shaders::{WgslModule, MODULES};
use shadowlab_core::technique::registry::{INDIRECT_REGISTRY, REGISTRY};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every module: the shared ones, then each registered technique's (an entry may share its folder's list with
/// another entry: each module once).
fn all_modules() -> Vec<(String, WgslModule)> {
    let mut modules: Vec<(String, WgslModule)> = MODULES.iter().map(|m| ("shared".to_string(), *m)).collect();
    for entry in REGISTRY.iter().chain(INDIRECT_REGISTRY) {
        for m in entry.shaders {
            if !modules.iter().any(|(_, known)| known.name == m.name) {
                modules.push((entry.key.to_string(), *m));
            }
        }
    }
    modules
}

#[test]
fn every_shader_module_validates() {
    let mut failures = Vec::new();
    let modules = all_modules();
    for (owner, m) in &modules {
        let module = match naga::front::wgsl::parse_str(m.source) {
            Ok(module) => module,
            Err(e) => {
                failures.push(format!("{owner}/{}: parse error:\n{}", m.name, e.emit_to_string(m.source)));
                continue;
            }
        };
        let mut validator =
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default());
        if let Err(e) = validator.validate(&module) {
            failures.push(format!("{owner}/{}: validation error:\n{}", m.name, e.emit_to_string(m.source)));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(modules.len() >= 20, "expected the shared and the techniques' modules, found {}", modules.len());
}

fn wgsl_files(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            wgsl_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            found.push(path);
        }
    }
}

#[test]
fn every_wgsl_file_is_used_by_a_module() {
    let root = repo_root();
    let used: Vec<&str> = all_modules().iter().flat_map(|(_, m)| m.files.iter().copied()).collect::<Vec<_>>();
    let mut files = Vec::new();
    wgsl_files(&root.join("shaders"), &mut files);
    wgsl_files(&root.join("core/src"), &mut files);
    assert!(files.len() >= 20, "expected the shader files under {}", root.display());
    for path in files {
        let relative = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
        assert!(used.contains(&relative.as_str()), "{relative} is not part of any module");
    }
    for file in used {
        assert!(root.join(file).is_file(), "a module names {file}, which does not exist");
    }
}

/// A technique's own WGSL (every file of its modules outside the shared `shaders/`) lies in one folder
/// `core/src/technique/<name>/`, and no shared module uses a file of a technique's folder.
#[test]
fn a_techniques_shaders_live_in_its_folder() {
    for entry in REGISTRY.iter().chain(INDIRECT_REGISTRY) {
        let own: Vec<&str> =
            entry.shaders.iter().flat_map(|m| m.files.iter().copied()).filter(|f| !f.starts_with("shaders/")).collect();
        let folders: std::collections::BTreeSet<&str> =
            own.iter().map(|f| f.rsplit_once('/').map_or("", |(dir, _)| dir)).collect();
        assert!(folders.len() <= 1, "{}: its WGSL is spread over {folders:?}", entry.key);
        for folder in folders {
            assert!(
                folder.starts_with("core/src/technique/") && folder.matches('/').count() == 3,
                "{}: its WGSL lives in {folder}, not in a technique folder",
                entry.key
            );
        }
        for m in entry.shaders {
            assert!(!m.files.is_empty() && !m.source.is_empty(), "{}: module {} is empty", entry.key, m.name);
        }
    }
    for m in MODULES {
        for file in m.files {
            assert!(file.starts_with("shaders/"), "shared module {} uses {file} of a technique's folder", m.name);
        }
    }
}

fn rust_files(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            found.push(path);
        }
    }
}

/// "Adding a technique touches its folder and one registry entry": outside `core/src/technique/<name>/` and
/// `registry.rs`, no source file of `core/src` or `app/src` names the module `technique::<name>` (tests and
/// benches may reach into a technique's internals; they are not part of the house).
#[test]
fn only_the_registry_names_a_technique_module() {
    let root = repo_root();
    let technique_dir = root.join("core/src/technique");
    let folders: Vec<String> = std::fs::read_dir(&technique_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(folders.len() >= 9, "expected the technique folders in {}", technique_dir.display());
    let mut sources = Vec::new();
    rust_files(&root.join("core/src"), &mut sources);
    rust_files(&root.join("app/src"), &mut sources);
    let mut offenders = Vec::new();
    for path in sources {
        let relative = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
        if relative == "core/src/technique/registry.rs" {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for folder in &folders {
            if relative.starts_with(&format!("core/src/technique/{folder}/")) {
                continue;
            }
            let named =
                [format!("technique::{folder}::"), format!("technique::{folder};"), format!("super::{folder}::")];
            // A technique folder may use another technique's module only through `super::` from inside the
            // technique tree; that is a dependency between techniques, listed here too.
            if named.iter().any(|n| text.contains(n.as_str())) {
                offenders.push(format!("{relative} names technique::{folder}"));
            }
        }
    }
    assert!(offenders.is_empty(), "technique modules named outside their folder:\n{}", offenders.join("\n"));
}
