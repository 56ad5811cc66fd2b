//! CPU-only: every `.wgsl` file under `shaders/` is part of a pass module, and every pass module
//! parses and validates with naga (the same front end wgpu uses), with the default and the
//! alternative values of its pipeline constants.

use myriad_gpu::shaders::{COMMON, PassShader};
use std::path::Path;

fn validate(name: &str, source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: WGSL parse error:\n{}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: validation error:\n{}", e.emit_to_string(source)));
    module
}

#[test]
fn every_pass_module_validates() {
    for pass in PassShader::ALL {
        let module = validate(pass.file_name(), &pass.source());
        assert!(
            !module.entry_points.is_empty(),
            "{} has no entry point",
            pass.file_name()
        );
    }
}

#[test]
fn every_wgsl_file_on_disk_is_compiled_in() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    let mut on_disk = Vec::new();
    for dir in [root.clone(), root.join("common")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "wgsl") {
                let relative = path
                    .strip_prefix(&root)
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                let text = std::fs::read_to_string(&path).unwrap();
                on_disk.push((relative, text));
            }
        }
    }
    let mut known: Vec<(String, String)> = COMMON
        .iter()
        .map(|(n, t)| (n.to_string(), t.to_string()))
        .collect();
    known.extend(
        PassShader::ALL
            .iter()
            .map(|p| (p.file_name().to_string(), p.own_source().to_string())),
    );
    on_disk.sort();
    known.sort();
    assert_eq!(
        on_disk.iter().map(|f| &f.0).collect::<Vec<_>>(),
        known.iter().map(|f| &f.0).collect::<Vec<_>>(),
        "shaders/ and the compiled-in list differ"
    );
    assert_eq!(on_disk, known, "a compiled-in shader differs from its file");
}

#[test]
fn pipeline_constants_are_declared_where_the_renderer_sets_them() {
    let overrides = |pass: PassShader| -> Vec<String> {
        let module = validate(pass.file_name(), &pass.source());
        module
            .overrides
            .iter()
            .filter_map(|(_, o)| o.name.clone())
            .collect()
    };
    for name in ["MODE", "HEAT_MAP", "HAS_SPOTS"] {
        assert!(
            overrides(PassShader::Deferred).contains(&name.to_string()),
            "deferred lacks {name}"
        );
    }
    for name in ["MODE", "HAS_SPOTS"] {
        assert!(
            overrides(PassShader::Forward).contains(&name.to_string()),
            "forward lacks {name}"
        );
    }
}

#[test]
fn a_broken_shader_is_rejected() {
    // The check above can fail: a type error in otherwise valid text is caught.
    let broken = PassShader::Deferred.source().replace(
        "let start = cluster_offsets[cluster];",
        "let start = cluster_offsets[cluster] + 1.0;",
    );
    let module = naga::front::wgsl::parse_str(&broken);
    let rejected = match module {
        Err(_) => true,
        Ok(m) => naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&m)
        .is_err(),
    };
    assert!(rejected);
}
