//! The passes of a frame as commands: bind groups over the renderer's buffers and G-buffer, then
//! the G-buffer, deferred shading and forward passes (each with its timestamp writes).

use super::{FrameDesc, Renderer};
use crate::profiling::profile_span;
use crate::scene::GpuScene;
use crate::targets::GBuffer;
use crate::timing::TimedPass;

impl Renderer {
    pub(super) fn lights_bind_group(&self, device: &wgpu::Device) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = [
            &self.lights,
            &self.offsets,
            &self.counts,
            &self.indices,
            &self.slice_edges,
        ]
        .iter()
        .enumerate()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: b.buffer().as_entire_binding(),
        })
        .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lights and lists"),
            layout: &self.pipelines.lights_layout,
            entries: &entries,
        })
    }

    pub(super) fn deferred_bind_group(
        &self,
        device: &wgpu::Device,
        gbuffer: &GBuffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("deferred inputs"),
            layout: &self.pipelines.deferred_inputs_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.frame_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&gbuffer.albedo),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&gbuffer.normal),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&gbuffer.material),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&gbuffer.depth),
                },
            ],
        })
    }

    pub(super) fn encode_gbuffer(&mut self, encoder: &mut wgpu::CommandEncoder, scene: &GpuScene) {
        profile_span!("encode pass: G-buffer");
        let gbuffer = self
            .gbuffer
            .as_ref()
            .expect("G-buffer created before encoding");
        let clear = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &[
                clear(&gbuffer.albedo),
                clear(&gbuffer.normal),
                clear(&gbuffer.material),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &gbuffer.depth,
                depth_ops: Some(wgpu::Operations {
                    // Reversed Z: 0 is the far plane, and "nothing drawn".
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: self.timer.writes(TimedPass::GBuffer),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipelines.gbuffer);
        pass.set_bind_group(0, &self.frame_group, &[]);
        pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
        pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for draw in &scene.opaque {
            pass.set_bind_group(1, &scene.material_groups[draw.material as usize], &[]);
            pass.draw_indexed(
                draw.first_index..draw.first_index + draw.index_count,
                0,
                0..1,
            );
        }
    }

    /// The deferred shading pass into `target`, a view of `format` (as `check_target` found).
    pub(super) fn encode_shading(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        profile_span!("encode pass: deferred shading");
        let has_spots = self.shades_spots(frame);
        let timestamps = self.timer.writes(TimedPass::Shading);
        let pipeline =
            self.pipelines
                .deferred(device, format, frame.mode, frame.heat_map, has_spots);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("deferred shading"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, self.deferred_inputs.as_ref(), &[]);
        pass.set_bind_group(1, self.lights_group.as_ref(), &[]);
        pass.draw(0..3, 0..1);
    }

    /// The forward pass of blended geometry into `target`, a view of `format`.
    pub(super) fn encode_forward(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        profile_span!("encode pass: forward");
        let gbuffer = self
            .gbuffer
            .as_ref()
            .expect("G-buffer created before encoding");
        scene.blended_back_to_front(frame.camera.position, &mut self.scratch_draws);
        let has_spots = self.shades_spots(frame);
        let timestamps = self.timer.writes(TimedPass::Forward);
        let pipeline = self
            .pipelines
            .forward(device, format, frame.mode, has_spots);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("forward"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(forward_depth(&gbuffer.depth)),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.frame_group, &[]);
        pass.set_bind_group(1, self.lights_group.as_ref(), &[]);
        pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
        pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for draw in &self.scratch_draws {
            pass.set_bind_group(2, &scene.material_groups[draw.material as usize], &[]);
            pass.draw_indexed(
                draw.first_index..draw.first_index + draw.index_count,
                0,
                0..1,
            );
        }
    }
}

/// The forward pass's depth attachment: the G-buffer's depth, loaded, tested against, kept.
pub(super) fn forward_depth(
    depth: &wgpu::TextureView,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view: depth,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}
