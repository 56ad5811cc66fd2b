//! What a render needs before its first frame: geometry, camera, grid and lights, from the
//! default scene (the generated atrium) or any glTF model.
//!
//! The default scene (decided here, used by the main job and the GPU tests): `assets/atrium.glb`
//! — the 12 lights authored in it (10 warm lamps, 2 spots) plus lights on its surfaces (area
//! weighted, 0.2 m off the surface, radii 0.5–3 m, random hues, seed 1) up to the requested
//! count — seen from its camera "Main" with a 24×12×16 log grid over the camera's depth range.

use anyhow::{Context, Result};
use myriad_cluster_math::glam::{UVec3, Vec3};
use myriad_gpu::SceneGeometry;
use myriad_scene::{
    Aabb, Camera, ClusterGrid, DepthSlicing, LightField, Lights, Model, Placement, RadiusRule,
    SurfaceSampler,
};

use super::geometry::scene_geometry;

/// A scene ready to render.
#[derive(Clone, Debug)]
pub struct RenderScene {
    /// What it is, for reports.
    pub name: String,
    /// Flattened geometry.
    pub geometry: SceneGeometry,
    /// The camera (its size is the render size).
    pub camera: Camera,
    /// The cluster grid.
    pub grid: ClusterGrid,
    /// The lights.
    pub lights: Lights,
    /// World bounds of each alpha-blended draw: where the forward pass may shade.
    pub blended_bounds: Vec<Aabb>,
}

/// Grid of the default scene (the paper's smallest clustered configuration).
pub const DEFAULT_GRID: UVec3 = UVec3::new(24, 12, 16);

impl RenderScene {
    /// The default scene with `lights` lights at `width × height` (the atrium is generated in
    /// code and equals `assets/atrium.glb` byte for byte, so no file is needed).
    pub fn default_scene(lights: usize, width: u32, height: u32) -> Result<Self> {
        Self::from_model(
            &myriad_scene::atrium(),
            "default scene (atrium)",
            None,
            lights,
            1,
            width,
            height,
        )
    }

    /// A model's scene: its camera `camera` (by name; default its first, or without a
    /// perspective one [`Model::view_of_bounds`]) at `width × height`, its own lights then
    /// surface lights up to `lights` in all (drawn from `seed`, on the faces
    /// [`SurfaceSampler::for_view`] keeps for that camera: two cameras of a model may get
    /// different lights).
    pub fn from_model(
        model: &Model,
        name: &str,
        camera: Option<&str>,
        lights: usize,
        seed: u64,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let camera = match camera {
            Some(c) => {
                let index = model.camera_index(c).with_context(|| {
                    format!(
                        "{name}: no camera named {c:?}; it has {}",
                        model.camera_names()
                    )
                })?;
                model.camera(index, width, height).with_context(|| {
                    format!("{name}: camera {c:?} is orthographic; a perspective one is needed")
                })?
            }
            // As `myriad scene` does: the first camera, or a view down the bounds' long axis.
            None => {
                model
                    .camera_or_view(0, width, height)
                    .with_context(|| {
                        format!(
                            "{name}: draws nothing and has no camera, so there is no view to \
                             render; give a model with geometry or a camera (`myriad info` \
                             lists what a model has)"
                        )
                    })?
                    .0
            }
        };
        let grid = ClusterGrid::try_new(DEFAULT_GRID, DepthSlicing::Log, camera.near, camera.far)
            .with_context(|| format!("{name}: its camera"))?;
        let mut all = Lights::new();
        for light in model.lights.iter().take(lights) {
            all.push(light);
        }
        let extra = lights - all.len();
        if extra > 0 {
            // With the camera inside the model, none on faces turned away from it whose lights
            // would lie outside (the outside of the atrium's outer walls), as `myriad scene`
            // places them.
            let offset = 0.2;
            let field = LightField::new(Placement::Surfaces {
                surfaces: SurfaceSampler::for_view(model, camera.position, offset),
                offset,
            })
            .with_radius(RadiusRule::Uniform { min: 0.5, max: 3.0 });
            if let Some(problem) = field.problem() {
                anyhow::bail!("{name}: cannot place {extra} lights on its surfaces: {problem}");
            }
            let first = all.len() as u32;
            for (k, light) in field.generate(extra, seed).iter().enumerate() {
                all.push(light.with_source_index(first + k as u32));
            }
        }
        let geometry = scene_geometry(model);
        Ok(Self {
            name: name.to_string(),
            blended_bounds: blended_bounds(&geometry),
            geometry,
            camera,
            grid,
            lights: all,
        })
    }

    /// A scene file's (or preset's) camera, grid and lights, drawn in `model`'s geometry.
    pub fn from_scene(model: &Model, name: &str, scene: myriad_scene::Scene) -> Self {
        let geometry = scene_geometry(model);
        Self {
            name: name.to_string(),
            blended_bounds: blended_bounds(&geometry),
            geometry,
            camera: scene.camera,
            grid: scene.grid,
            lights: scene.lights,
        }
    }

    /// The same scene at another image size (same camera otherwise).
    pub fn with_size(mut self, width: u32, height: u32) -> Self {
        self.camera.width = width;
        self.camera.height = height;
        self
    }

    /// Whether any geometry is alpha-blended (the forward pass has work).
    pub fn has_blended(&self) -> bool {
        !self.blended_bounds.is_empty()
    }

    /// The same scene with a different grid over the same depth range.
    pub fn with_grid(mut self, dims: UVec3, slicing: DepthSlicing) -> Self {
        self.grid = ClusterGrid::new(dims, slicing, self.grid.near(), self.grid.far())
            .with_outer_slices(self.grid.outer_slices());
        self
    }
}

/// World bounds of every blended draw's vertices: what [`crate::render::fitted_grid`] and
/// [`crate::render::mark_active`] need besides the depth buffer, which blended geometry is not
/// drawn into. An engine running the prepass savings itself passes these; an empty slice is
/// right only when nothing is blended (the atrium's glass and banners were left unlit, 109/255
/// off, in a drop-in review that passed `&[]`).
pub fn blended_bounds(geometry: &SceneGeometry) -> Vec<Aabb> {
    geometry
        .draws
        .iter()
        .filter(|d| geometry.materials[d.material as usize].blend == myriad_gpu::Blend::Blended)
        .map(|d| {
            let range = d.first_index as usize..(d.first_index + d.index_count) as usize;
            Aabb::from_points(
                geometry.indices[range]
                    .iter()
                    .map(|&i| Vec3::from_array(geometry.vertices[i as usize].position)),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_without_a_camera_is_rendered_from_the_view_of_its_bounds() {
        let mut model = myriad_scene::atrium();
        model.cameras.clear();
        let scene = RenderScene::from_model(&model, "no camera", None, 10, 1, 64, 32).unwrap();
        assert_eq!(Some(scene.camera), model.view_of_bounds(64, 32));
        assert_eq!(scene.lights.len(), 10);
        // A camera asked for by name must exist.
        let err = RenderScene::from_model(&model, "no camera", Some("Main"), 10, 1, 64, 32)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("no camera named \"Main\"; it has none"),
            "{err}"
        );
        // Listed as `myriad scene` lists them, not as a Rust array.
        let atrium = myriad_scene::atrium();
        let err = RenderScene::from_model(&atrium, "atrium", Some("nope"), 10, 1, 64, 32)
            .unwrap_err()
            .to_string();
        let names: Vec<_> = atrium.cameras.iter().map(|c| c.name.as_str()).collect();
        assert!(atrium.cameras.len() > 1);
        assert!(
            err.ends_with(&format!("it has {}", names.join(", "))),
            "{err}"
        );
        // A model with nothing to draw and no camera says what would do.
        let mut empty = myriad_scene::atrium();
        empty.cameras.clear();
        empty.meshes.clear();
        empty.instances.clear();
        let err = RenderScene::from_model(&empty, "empty", None, 0, 1, 64, 32)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("give a model with geometry or a camera"),
            "{err}"
        );
    }

    /// A scene has the model's own lights first, then surface lights up to the count asked for,
    /// numbered on from the model's (`source_index` is the row); a model without surfaces renders
    /// with its own lights, and only asking for more than it has is refused.
    #[test]
    fn surface_lights_fill_up_to_the_count_after_the_models_own() {
        let mut model = myriad_scene::atrium();
        let own = model.lights.len();
        assert!(own > 0);
        let scene = RenderScene::from_model(&model, "atrium", None, own + 100, 7, 64, 32).unwrap();
        assert_eq!(scene.lights.len(), own + 100);
        assert_eq!(scene.lights.x[..own], model.lights.x[..]);
        let rows: Vec<u32> = (0..(own + 100) as u32).collect();
        assert_eq!(scene.lights.source_index, rows);

        model.meshes.clear();
        model.instances.clear();
        let bare = RenderScene::from_model(&model, "bare", None, own, 7, 64, 32).unwrap();
        assert_eq!(bare.lights.len(), own);
        let err = RenderScene::from_model(&model, "bare", None, own + 1, 7, 64, 32)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("cannot place 1 lights on its surfaces"),
            "{err}"
        );
    }

    /// The blended bounds are one box per alpha-blended draw, around that draw's vertices, and
    /// none for opaque draws: a model without blended materials has no forward-pass work.
    #[test]
    fn blended_bounds_box_the_blended_draws_only() {
        let mut model = myriad_scene::atrium();
        let scene = RenderScene::from_model(&model, "atrium", None, 10, 1, 64, 32).unwrap();
        let geometry = &scene.geometry;
        let blended: Vec<_> = geometry
            .draws
            .iter()
            .filter(|d| geometry.materials[d.material as usize].blend == myriad_gpu::Blend::Blended)
            .collect();
        assert!(!blended.is_empty() && blended.len() < geometry.draws.len());
        assert!(scene.has_blended());
        assert_eq!(scene.blended_bounds.len(), blended.len());
        for (bounds, draw) in scene.blended_bounds.iter().zip(blended) {
            // A draw's centre is the middle of its vertices' box.
            let middle = (bounds.min + bounds.max) * 0.5;
            assert!(
                (middle - draw.center).length() < 1e-4,
                "{bounds:?}, {draw:?}"
            );
        }
        for material in &mut model.materials {
            material.alpha_mode = myriad_scene::AlphaMode::Opaque;
        }
        let opaque = RenderScene::from_model(&model, "opaque atrium", None, 10, 1, 64, 32).unwrap();
        assert!(!opaque.has_blended() && opaque.blended_bounds.is_empty());
    }
}
