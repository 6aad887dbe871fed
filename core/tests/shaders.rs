//! Every composed WGSL module validates with naga, and every `.wgsl` file in `shaders/` is part of one.

use shadowlab_core::shaders::MODULES;

#[test]
fn every_shader_module_validates() {
    let mut failures = Vec::new();
    for (name, _, source) in MODULES {
        let module = match naga::front::wgsl::parse_str(source) {
            Ok(m) => m,
            Err(e) => {
                failures.push(format!("{name}: parse error:\n{}", e.emit_to_string(source)));
                continue;
            }
        };
        let mut validator =
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default());
        if let Err(e) = validator.validate(&module) {
            failures.push(format!("{name}: validation error:\n{}", e.emit_to_string(source)));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn every_wgsl_file_is_used_by_a_module() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let used: Vec<&str> = MODULES.iter().flat_map(|(_, files, _)| files.iter().copied()).collect();
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.ends_with(".wgsl") {
            count += 1;
            assert!(used.contains(&name.as_str()), "shaders/{name} is not part of any module in core/src/shaders.rs");
        }
    }
    assert!(count >= 6, "expected the shader files in {}", dir.display());
}
