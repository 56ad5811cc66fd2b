//! Refusing a render target wgpu would reject, as an error instead of a panic.
//!
//! wgpu 30 cannot tell a `TextureView`'s format, mip level or sample count, only its texture's.
//! A view whose sRGB-ness differs from the renderer's output format, a view of a lower mip, or a
//! multisampled texture then passed the renderer's own checks and panicked inside wgpu's
//! validation in the middle of the frame (audit f3), or, for a lower mip without a forward pass,
//! shaded pixels of the wrong size with `Ok`. So the first frame into a target records both
//! shading passes' attachments (the forward pass's with the G-buffer's depth, whether it runs or
//! not) and pipelines into a throwaway encoder under a validation error scope, never submitted,
//! and refuses the frame with wgpu's own message when that fails.
//! A target already accepted at this G-buffer size is not checked again: the renderer keeps a
//! clone of the last accepted view (which keeps that one texture alive until another target is
//! drawn). A swap chain hands out a new view every frame, so there each frame pays for the check:
//! one throwaway encoder with two empty passes, nothing submitted.

use super::Renderer;
use super::passes::forward_depth;
use crate::FrameDesc;
use crate::error::GpuError;
use std::future::Future;
use std::task::{Context, Poll, Waker};

/// A target the shading passes were recorded into without a validation error.
#[derive(Debug, PartialEq)]
pub(super) struct CheckedTarget {
    view: wgpu::TextureView,
    gbuffer_size: (u32, u32),
    forward: bool,
}

impl Renderer {
    /// Checks that `target` works as the colour attachment of the deferred pass and of the
    /// forward pass with the G-buffer's depth (both attachments are always checked; only the
    /// forward pipeline is left out without `forward`). Call after the G-buffer
    /// exists at the frame's size and before anything is staged.
    pub(super) fn check_target(
        &mut self,
        device: &wgpu::Device,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
        forward: bool,
    ) -> Result<(), GpuError> {
        let gbuffer = self.gbuffer.as_ref().expect("G-buffer created first");
        let key = CheckedTarget {
            view: target.clone(),
            gbuffer_size: gbuffer.size,
            forward,
        };
        if self.checked_target.as_ref() == Some(&key) {
            return Ok(());
        }
        let has_spots = self.shades_spots(frame);
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
            let pipeline = self
                .pipelines
                .deferred(device, frame.mode, frame.heat_map, has_spots);
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
                pass.set_pipeline(self.pipelines.forward(device, frame.mode, has_spots));
            }
        }
        drop(encoder.finish());
        if let Some(error) = ready(scope.pop()).flatten() {
            return Err(GpuError::InvalidInput(format!(
                "the target cannot be drawn into (a single-sample view of mip 0 of a \
                 RENDER_ATTACHMENT texture, in exactly the renderer's format {:?}, is needed): \
                 {error}",
                self.pipelines.output_format()
            )));
        }
        self.checked_target = Some(key);
        Ok(())
    }
}

/// The value of a future that is ready at once (a native device's error scope resolves
/// synchronously); `None` when it is not, which then refuses nothing.
fn ready<T>(future: impl Future<Output = T>) -> Option<T> {
    let mut future = std::pin::pin!(future);
    match future
        .as_mut()
        .poll(&mut Context::from_waker(Waker::noop()))
    {
        Poll::Ready(value) => Some(value),
        Poll::Pending => None,
    }
}
