//! Refusing a render target wgpu would reject, as an error instead of a panic, and finding the
//! format the passes must draw it in.
//!
//! wgpu 30 cannot tell a `TextureView`'s format, mip level or sample count, only its texture's.
//! A view whose sRGB-ness differs from its texture's (`view_formats`), a view of a lower mip, or a
//! multisampled texture then passed the renderer's own checks and panicked inside wgpu's
//! validation in the middle of the frame (audit f3), as did a texture of another device (a
//! texture cannot be asked for its device), or, for a lower mip without a forward pass,
//! shaded pixels of the wrong size with `Ok`. So the first frame into a target records both
//! shading passes' attachments (the forward pass's with the G-buffer's depth, whether it runs or
//! not) and pipelines into a throwaway encoder under a validation error scope, never submitted,
//! and refuses the frame with wgpu's own message when that fails.
//!
//! The same recording finds the view's format: the texture's, or its sRGB twin where the view
//! reinterprets it. The twin is tried second (first when it is the renderer's own format, the
//! usual reason for such a view), so a reinterpreting view costs one failed recording and the
//! pipelines of a format it does not use.
//!
//! A target already accepted at this G-buffer size is not checked again: the renderer keeps a
//! clone of the last accepted view (which keeps that one texture alive until another target is
//! drawn). A swap chain hands out a new view every frame, so there each frame pays for the check:
//! one throwaway encoder with two empty passes (two, for a reinterpreting view), nothing
//! submitted.

use super::Renderer;
use super::passes::forward_depth;
use crate::FrameDesc;
use crate::error::GpuError;
use crate::pipelines::drawable_format;
use std::future::Future;
use std::task::{Context, Poll, Waker};

/// A target the shading passes were recorded into without a validation error.
#[derive(Debug)]
pub(super) struct CheckedTarget {
    view: wgpu::TextureView,
    gbuffer_size: (u32, u32),
    forward: bool,
    /// The format the passes draw the view in.
    format: wgpu::TextureFormat,
}

impl Renderer {
    /// Checks that `target` works as the colour attachment of the deferred pass and of the
    /// forward pass with the G-buffer's depth (both attachments are always checked; only the
    /// forward pipeline is left out without `forward`), and returns the format to draw it in.
    /// Call after the G-buffer exists at the frame's size, after the texture's own format was
    /// found drawable, and before anything is staged.
    pub(super) fn check_target(
        &mut self,
        device: &wgpu::Device,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
        forward: bool,
    ) -> Result<wgpu::TextureFormat, GpuError> {
        let gbuffer_size = self.gbuffer.as_ref().expect("G-buffer created first").size;
        if let Some(checked) = &self.checked_target
            && checked.view == *target
            && checked.gbuffer_size == gbuffer_size
            && checked.forward == forward
        {
            return Ok(checked.format);
        }
        let own = target.texture().format();
        let twin = if own.is_srgb() {
            own.remove_srgb_suffix()
        } else {
            own.add_srgb_suffix()
        };
        // A twin the device cannot draw is not tried (nor one a format lacks).
        let twin = (twin != own && drawable_format(device, twin).is_none()).then_some(twin);
        let order = match twin {
            Some(twin) if twin == self.pipelines.output_format() => [Some(twin), Some(own)],
            twin => [Some(own), twin],
        };
        let mut own_error = None;
        for format in order.into_iter().flatten() {
            match self.record_passes(device, frame, target, forward, format) {
                None => {
                    self.checked_target = Some(CheckedTarget {
                        view: target.clone(),
                        gbuffer_size,
                        forward,
                        format,
                    });
                    return Ok(format);
                }
                Some(error) if format == own => own_error = Some(error),
                Some(_) => {}
            }
        }
        Err(GpuError::InvalidInput(format!(
            "the target cannot be drawn into (a single-sample view of mip 0 of a \
             RENDER_ATTACHMENT texture of this renderer's device, in the texture's format \
             {own:?} or its sRGB twin, is needed): {}",
            own_error.expect("the texture's own format is always tried")
        )))
    }

    /// Records both shading passes into `target` as a view of `format` in a throwaway encoder,
    /// never submitted: wgpu's validation error, or `None`.
    fn record_passes(
        &mut self,
        device: &wgpu::Device,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
        forward: bool,
        format: wgpu::TextureFormat,
    ) -> Option<wgpu::Error> {
        let has_spots = self.shades_spots(frame);
        let gbuffer = self.gbuffer.as_ref().expect("G-buffer created first");
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("target check (never submitted)"),
        });
        let color = [Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })];
        {
            let pipeline =
                self.pipelines
                    .deferred(device, format, frame.mode, frame.heat_map, has_spots);
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("target check: deferred"),
                color_attachments: &color,
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
        }
        {
            // Always paired with the G-buffer's depth, even when no forward pass runs: wgpu then
            // compares the view's own size (a lower mip's) with the camera's, which the deferred
            // pass alone never does (it would shade the pixels of another size, with `Ok`).
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("target check: forward"),
                color_attachments: &color,
                depth_stencil_attachment: Some(forward_depth(&gbuffer.depth)),
                ..Default::default()
            });
            if forward {
                pass.set_pipeline(
                    self.pipelines
                        .forward(device, format, frame.mode, has_spots),
                );
            }
        }
        drop(encoder.finish());
        ready(scope.pop()).flatten()
    }
}

/// The value of a future that is ready at once (a native device's error scope resolves
/// synchronously); `None` when it is not, which then refuses nothing.
pub(super) fn ready<T>(future: impl Future<Output = T>) -> Option<T> {
    let mut future = std::pin::pin!(future);
    match future
        .as_mut()
        .poll(&mut Context::from_waker(Waker::noop()))
    {
        Poll::Ready(value) => Some(value),
        Poll::Pending => None,
    }
}
