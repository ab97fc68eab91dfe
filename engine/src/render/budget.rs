//! The memory a renderer will need, checked against the device before anything is allocated.
//!
//! A driver refuses an allocation larger than `maxMemoryAllocationSize` (lavapipe: 2 GiB) with
//! a bare `VK_ERROR_OUT_OF_DEVICE_MEMORY`, after the run has started. The sizes here are asked
//! of the driver itself (`vkGetDeviceImageMemoryRequirements`), for the exact images the
//! renderer will create, so the estimate cannot drift from what is allocated; a request that
//! cannot fit is refused up front, naming the setting that sizes it and the largest value that
//! would fit.

use crate::scene::{CubeSettings, Scene};
use crate::vk::device::Device;
use crate::vk::image::ImageDesc;
use crate::vk::GpuError;

use super::targets::{CubeTarget, IdCube, ViewTarget, DIRECTION_FORMAT, VIEW_FORMAT};
use super::PAIR_SIZE;

/// One image the renderer will create, with the setting that sizes it.
struct Planned {
    what: String,
    /// The setting and its value, e.g. "--cube-size = 8192".
    setting: String,
    /// Sized by the cube's face size (the message then names the largest size that fits).
    cube: bool,
    bytes: u64,
}

/// Checks every render target of `scene` against the device's allocation limit and its
/// device-local heap. `cube_setting` names where the face size came from (a command-line
/// option or the scene's field), for the message.
pub fn check_targets(
    device: &Device,
    scene: &Scene,
    cube_setting: &str,
    id_cube: bool,
) -> Result<(), GpuError> {
    let limits = &device.info.limits;
    check_dimensions(device, scene, cube_setting)?;
    let plan = planned_targets(device, scene, cube_setting, id_cube);
    for p in &plan {
        if p.bytes > limits.max_memory_allocation_bytes {
            let hint = if p.cube {
                largest_cube_hint(device, &scene.cube)
            } else {
                String::new()
            };
            return Err(GpuError::TooLarge(format!(
                "{} ({}) needs {} in one allocation, more than this device allows \
                 (maxMemoryAllocationSize {}){hint}",
                p.what,
                p.setting,
                bytes_text(p.bytes),
                bytes_text(limits.max_memory_allocation_bytes)
            )));
        }
    }
    let total: u64 = plan.iter().map(|p| p.bytes).sum();
    if total > limits.device_local_heap_bytes {
        return Err(GpuError::TooLarge(format!(
            "the render targets need {} together ({cube_setting} = {} px per cube face), more \
             than this device's memory ({}); lower {cube_setting} or the view resolutions",
            bytes_text(total),
            scene.cube.face_size_px,
            bytes_text(limits.device_local_heap_bytes)
        )));
    }
    Ok(())
}

/// Image sides within the device's limits (the memory query itself needs valid images).
fn check_dimensions(device: &Device, scene: &Scene, cube_setting: &str) -> Result<(), GpuError> {
    let limits = &device.info.limits;
    let size = scene.cube.face_size_px;
    if size > limits.max_image_dimension_cube {
        return Err(GpuError::TooLarge(format!(
            "{cube_setting} = {size} px exceeds this device's largest cube face \
             (maxImageDimensionCube {})",
            limits.max_image_dimension_cube
        )));
    }
    let views = [
        ("observer.resolution", scene.observer.resolution),
        ("sensor.resolution", scene.sensor.resolution),
    ];
    for (setting, [w, h]) in views {
        if w.max(h) > limits.max_image_dimension_2d {
            return Err(GpuError::TooLarge(format!(
                "{setting} = [{w}, {h}] exceeds this device's largest image side \
                 (maxImageDimension2D {})",
                limits.max_image_dimension_2d
            )));
        }
    }
    Ok(())
}

/// Checks one host-visible buffer of `bytes` (a frame's readback) before it is created.
pub fn check_buffer(device: &Device, what: &str, bytes: u64) -> Result<(), GpuError> {
    let limit = device.info.limits.max_memory_allocation_bytes;
    if bytes > limit {
        return Err(GpuError::TooLarge(format!(
            "{what} needs {} in one allocation, more than this device allows \
             (maxMemoryAllocationSize {}); read back less (e.g. no cube faces) or lower the \
             cube size",
            bytes_text(bytes),
            bytes_text(limit)
        )));
    }
    Ok(())
}

/// The images `Renderer::new` creates, in its order.
fn planned_targets(
    device: &Device,
    scene: &Scene,
    cube_setting: &str,
    id_cube: bool,
) -> Vec<Planned> {
    let mut plan = Vec::new();
    let mut add = |what: String, setting: String, desc: ImageDesc| {
        plan.push(Planned {
            what,
            setting,
            cube: desc.layers == 6,
            bytes: desc.memory_bytes(device),
        })
    };
    let cube = &scene.cube;
    let size = format!("{cube_setting} = {}", cube.face_size_px);
    add(
        "the cube map's colour".into(),
        size.clone(),
        CubeTarget::color_desc(cube),
    );
    add(
        "the cube map's depth".into(),
        size.clone(),
        CubeTarget::depth_desc(cube),
    );
    if id_cube {
        add("the id cube".into(), size, IdCube::desc(cube));
    }
    let views = [
        ("observer", "observer.resolution", scene.observer.resolution),
        ("sensor", "sensor.resolution", scene.sensor.resolution),
        ("two-view", "the two-view image", PAIR_SIZE),
    ];
    for (name, setting, [w, h]) in views {
        let setting = format!("{setting} = [{w}, {h}]");
        let [color, depth] = ViewTarget::descs(VIEW_FORMAT, w, h);
        add(format!("the {name} image"), setting.clone(), color);
        add(format!("the {name} depth"), setting.clone(), depth);
        if name != "two-view" {
            let [directions, _] = ViewTarget::descs(DIRECTION_FORMAT, w, h);
            add(format!("the {name} lookup directions"), setting, directions);
        }
    }
    plan
}

/// ", the largest face size that fits is N": the largest size whose colour and depth images
/// each fit one allocation (binary search over sizes, asking the driver each time).
fn largest_cube_hint(device: &Device, cube: &CubeSettings) -> String {
    let limit = device.info.limits.max_memory_allocation_bytes;
    let fits = |size: u32| {
        let settings = CubeSettings {
            face_size_px: size,
            ..cube.clone()
        };
        CubeTarget::color_desc(&settings).memory_bytes(device) <= limit
            && CubeTarget::depth_desc(&settings).memory_bytes(device) <= limit
    };
    let (mut lo, mut hi) = (0u32, cube.face_size_px);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    match lo {
        0 => String::new(),
        n => format!("; the largest face size that fits is {n}"),
    }
}

/// Bytes for people: "3.22 GB"-style decimal units would disagree with the driver's
/// power-of-two limits, so binary units (KiB, MiB, GiB) with two decimals.
pub fn bytes_text(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.2} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::bytes_text;

    #[test]
    fn bytes_read_in_binary_units() {
        assert_eq!(bytes_text(0), "0 B");
        assert_eq!(bytes_text(1023), "1023 B");
        assert_eq!(bytes_text(1024), "1.00 KiB");
        assert_eq!(bytes_text(2 << 30), "2.00 GiB");
        assert_eq!(bytes_text(3 * (1 << 29)), "1.50 GiB");
    }
}
