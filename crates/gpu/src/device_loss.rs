//! Noticing that the device was lost, so that the renderer's calls say so.
//!
//! Why: once a device is lost (a driver reset, a GPU that hung, `Device::destroy`), wgpu turns
//! every later call into an invalid object or an error on the device. Without knowing, the
//! renderer reported the first frame after a loss as *running out of memory* (its staging copy
//! could not be mapped) and the next read-back panicked inside wgpu (`map_async` on an invalid
//! buffer raises a validation error, and wgpu's default handler panics). With the loss recorded,
//! every call of the renderer and every wait returns [`crate::GpuError::DeviceLost`] with wgpu's
//! reason and message instead, before it touches the device.
//!
//! wgpu reports a loss through one callback per device (`Device::set_device_lost_callback`,
//! which replaces any earlier one), called when the device next does its housekeeping (a poll,
//! a submit). Whose callback it is depends on whose device it is:
//! - `GpuContext::headless` makes the device, so it sets a callback that records the
//!   loss into the context (every clone shares the record).
//! - An engine's device ([`crate::GpuContext::from_device`]) keeps the engine's callback: the
//!   engine calls [`DeviceLossRecorder::record`] from it (get one with
//!   [`crate::GpuContext::loss_recorder`]), or lets the context set its own with
//!   [`crate::GpuContext::track_device_loss`] when it has none.
//!
//! The recorder holds no device (a callback that held one would keep its own device alive
//! through the device), only the shared record. The first loss recorded is kept.

use std::sync::{Arc, Mutex};

/// A lost device: wgpu's reason and message, as its device-lost callback gave them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceLoss {
    /// Why: `Destroyed` after `Device::destroy`, `Unknown` for a driver's loss.
    pub reason: wgpu::DeviceLostReason,
    /// wgpu's message (may be empty).
    pub message: String,
}

impl std::fmt::Display for DeviceLoss {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let reason = match self.reason {
            wgpu::DeviceLostReason::Destroyed => "destroyed",
            wgpu::DeviceLostReason::Unknown => "lost by the driver",
        };
        if self.message.is_empty() {
            write!(f, "{reason}")
        } else {
            write!(f, "{reason}: {}", self.message)
        }
    }
}

/// Where a device's loss is recorded; clones share one record. Call [`DeviceLossRecorder::record`]
/// from the device's lost callback.
#[derive(Clone, Debug, Default)]
pub struct DeviceLossRecorder(Arc<Mutex<Option<DeviceLoss>>>);

impl DeviceLossRecorder {
    /// Records that the device was lost (a second loss keeps the first's reason).
    pub fn record(&self, reason: wgpu::DeviceLostReason, message: impl Into<String>) {
        let mut slot = self
            .0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        slot.get_or_insert_with(|| DeviceLoss {
            reason,
            message: message.into(),
        });
    }

    /// The recorded loss, if the device was lost.
    pub fn loss(&self) -> Option<DeviceLoss> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .clone()
    }

    /// Sets `device`'s lost callback to record here (replacing any callback it had).
    pub(crate) fn watch(&self, device: &wgpu::Device) {
        let recorder = self.clone();
        device.set_device_lost_callback(move |reason, message| recorder.record(reason, message));
    }
}

#[cfg(test)]
mod tests {
    use super::DeviceLossRecorder;
    use wgpu::DeviceLostReason;

    #[test]
    fn the_first_loss_is_kept_and_every_clone_sees_it() {
        let recorder = DeviceLossRecorder::default();
        let clone = recorder.clone();
        assert_eq!(clone.loss(), None);
        recorder.record(DeviceLostReason::Unknown, "VK_ERROR_DEVICE_LOST");
        recorder.record(DeviceLostReason::Destroyed, "");
        let loss = clone.loss().expect("recorded through the other clone");
        assert_eq!(loss.reason, DeviceLostReason::Unknown);
        assert_eq!(loss.to_string(), "lost by the driver: VK_ERROR_DEVICE_LOST");
    }
}
