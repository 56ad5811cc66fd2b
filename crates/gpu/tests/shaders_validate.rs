//! CPU-only: every `.wgsl` file under `shaders/` is part of a pass module, and every pass module
//! parses and validates with naga (the same front end wgpu uses). Every combination of values its
//! pipeline constants can take (0 and 1 for each; they are all flags or two-way modes) is then
//! substituted exactly as wgpu does at pipeline creation (`process_overrides`) and translated to
//! SPIR-V, the path Vulkan takes: a variant that only breaks once its constant is known (code
//! compiled in by `HAS_SPOTS`, a branch only `MODE = 1` keeps) fails here, without a GPU.

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

/// The names of a module's pipeline-overridable constants.
fn override_names(module: &naga::Module) -> Vec<String> {
    module
        .overrides
        .iter()
        .filter_map(|(_, o)| o.name.clone())
        .collect()
}

/// Substitutes `constants` as wgpu does at pipeline creation, then writes SPIR-V.
fn translate(module: &naga::Module, constants: &[(String, f64)]) -> Result<Vec<u32>, String> {
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(module)
    .map_err(|e| e.to_string())?;
    let constants: naga::back::PipelineConstants = constants.iter().cloned().collect();
    let (resolved, resolved_info) =
        naga::back::pipeline_constants::process_overrides(module, &info, None, &constants)
            .map_err(|e| e.to_string())?;
    naga::back::spv::write_vec(
        &resolved,
        &resolved_info,
        &naga::back::spv::Options::default(),
        None,
    )
    .map_err(|e| e.to_string())
}

/// Every assignment of 0 or 1 to each of the module's pipeline constants.
fn variants(module: &naga::Module) -> Vec<Vec<(String, f64)>> {
    let names = override_names(module);
    (0u32..1 << names.len())
        .map(|bits| {
            names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.clone(), f64::from((bits >> i) & 1)))
                .collect()
        })
        .collect()
}

#[test]
fn every_pipeline_constant_variant_translates_to_spir_v() {
    let mut translated = 0;
    for pass in PassShader::ALL {
        let name = pass.file_name();
        let module = validate(name, &pass.source());
        for constants in variants(&module) {
            let words = translate(&module, &constants)
                .unwrap_or_else(|e| panic!("{name} with {constants:?}: {e}"));
            assert_eq!(words.first(), Some(&0x0723_0203), "{name}: not SPIR-V");
            translated += 1;
        }
    }
    // deferred: MODE × HEAT_MAP × HAS_SPOTS; forward: MODE × HAS_SPOTS; the others, one each.
    assert!(
        translated >= 8 + 4,
        "only {translated} variants were translated"
    );
}

#[test]
fn a_variant_that_breaks_only_once_its_constant_is_known_is_caught() {
    // Valid WGSL whose `MODE = 1` variant divides by zero at pipeline creation (in a constant
    // the shader uses: those are the ones wgpu evaluates).
    let source = PassShader::Forward
        .source()
        .replace(
            "override MODE: u32 = 0u;",
            "override MODE: u32 = 0u;\noverride BROKEN: u32 = 1u / (1u - MODE);",
        )
        .replace("if (MODE == 1u) {", "if (MODE == BROKEN) {");
    let module = validate("broken forward", &source);
    let with_mode = |mode: f64| vec![("MODE".to_string(), mode), ("HAS_SPOTS".to_string(), 1.0)];
    let outcomes: Vec<(f64, bool)> = [0.0, 1.0]
        .into_iter()
        .map(|mode| (mode, translate(&module, &with_mode(mode)).is_ok()))
        .collect();
    assert!(
        outcomes.iter().any(|&(m, ok)| m == 0.0 && ok),
        "{outcomes:?}"
    );
    assert!(
        outcomes.iter().any(|&(m, ok)| m == 1.0 && !ok),
        "{outcomes:?}"
    );
}

#[test]
fn every_wgsl_file_on_disk_is_compiled_in() {
    let root = Path::new(env!("MYRIAD_SHADER_DIR")).to_path_buf();
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
    let overrides = |pass: PassShader| override_names(&validate(pass.file_name(), &pass.source()));
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
