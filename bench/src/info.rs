//! `specchio info`: every Vulkan device, what it supports, and which one would be used.

use std::process::ExitCode;

use anyhow::Result;
use specchio::render::lookups;
use specchio::render::methods::Method;
use specchio::scene::Lookup;
use specchio::vk::device::{self, DeviceInfo, MIN_MESA_MAJOR};

use crate::probe;
use crate::records::{InfoDevice, InfoLookup, InfoMethod, InfoRecord};
use specchio::vk::instance::{Instance, InstanceDesc};

#[derive(clap::Args)]
pub struct Args {
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Enable the Khronos validation layer (also: SPECCHIO_VALIDATE=1); any message makes the
    /// command fail (exit 3).
    #[arg(long)]
    validate: bool,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let listed = list(args, instance);
    crate::validation::checked(&log, listed)
}

/// Prints every device; the instance is gone when it returns.
fn list(args: &Args, instance: std::sync::Arc<Instance>) -> Result<ExitCode> {
    let candidates = device::enumerate(&instance)?;
    // The device a command without `--device` would use.
    let default = device::choose(&instance, None).ok().map(|d| d.index);
    // Which cube methods each usable device can run (multiview is probed in a child process).
    let methods: Vec<Vec<(Method, Result<(), String>)>> = candidates
        .iter()
        .map(|c| match &c.rejected {
            None => Method::all()
                .map(|m| (m, probe::usable(m, &c.info)))
                .collect(),
            Some(_) => Vec::new(),
        })
        .collect();
    if args.json {
        let devices = candidates
            .iter()
            .zip(&methods)
            .map(|(c, ms)| InfoDevice {
                info: c.info.clone(),
                usable: c.rejected.is_none(),
                default: default == Some(c.info.index),
                rejected_because: c.rejected.clone(),
                mesa_too_old: mesa_too_old(&c.info),
                methods: ms
                    .iter()
                    .map(|(m, r)| InfoMethod {
                        method: *m,
                        usable: r.is_ok(),
                        reason: r.as_ref().err().cloned(),
                    })
                    .collect(),
                lookups: lookup_support(c)
                    .into_iter()
                    .map(|(lookup, why)| InfoLookup {
                        lookup,
                        usable: why.is_none(),
                        reason: why,
                    })
                    .collect(),
            })
            .collect();
        crate::say!("{}", serde_json::to_string_pretty(&InfoRecord { devices })?);
        return Ok(ExitCode::SUCCESS);
    }
    if candidates.is_empty() {
        crate::say!("no Vulkan device found (Debian: apt-get install mesa-vulkan-drivers)");
    }
    for (c, ms) in candidates.iter().zip(&methods) {
        print_device(
            &c.info,
            c.rejected.as_deref(),
            default == Some(c.info.index),
        );
        for (m, r) in ms {
            match r {
                Ok(()) => crate::say!("    method {:<20} usable", m.name()),
                Err(why) => crate::say!("    method {:<20} NOT USABLE: {why}", m.name()),
            }
        }
        for (l, why) in lookup_support(c) {
            match why {
                None => crate::say!("    lookup {:<20} usable", l.name()),
                Some(why) => crate::say!("    lookup {:<20} NOT USABLE: {why}", l.name()),
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Each mirror lookup on a usable device, with why it cannot run (none on a rejected device).
fn lookup_support(c: &device::Candidate) -> Vec<(Lookup, Option<String>)> {
    if c.rejected.is_some() {
        return Vec::new();
    }
    Lookup::ALL
        .into_iter()
        .map(|l| (l, lookups::missing_features(l, &c.info)))
        .collect()
}

fn mesa_too_old(info: &DeviceInfo) -> bool {
    device::mesa_major(info).is_some_and(|m| m < MIN_MESA_MAJOR)
}

fn print_device(i: &DeviceInfo, rejected: Option<&str>, default: bool) {
    let yes = |b: bool| if b { "yes" } else { "no" };
    let mark = if default { "  <- default" } else { "" };
    crate::say!("[{}] {} ({}){mark}", i.index, i.name, i.device_type);
    crate::say!("    --device:           {} (or {})", i.short_name, i.index);
    match rejected {
        Some(why) => crate::say!("    status:             NOT USABLE: {why}"),
        None => crate::say!("    status:             usable"),
    }
    crate::say!(
        "    driver:             {} {} (version {})",
        i.driver_name,
        i.driver_info,
        i.driver_version
    );
    crate::say!("    Vulkan:             {}", i.api_version);
    if mesa_too_old(i) {
        crate::say!("    WARNING:            Mesa {} is older than {MIN_MESA_MAJOR}; results may differ (see README)",
            i.mesa_version.as_deref().unwrap_or("?"));
    }
    let l = &i.limits;
    let f = &i.features;
    crate::say!("    limits:             cube {} px, 2D {} px, {} layers, {} B push constants, anisotropy {}x, timestamp {} ns",
        l.max_image_dimension_cube, l.max_image_dimension_2d, l.max_image_array_layers,
        l.max_push_constants_size, l.max_sampler_anisotropy, l.timestamp_period_ns);
    crate::say!(
        "    memory:             {} per allocation, {} device-local heap",
        specchio::render::budget::bytes_text(l.max_memory_allocation_bytes),
        specchio::render::budget::bytes_text(l.device_local_heap_bytes)
    );
    crate::say!(
        "    multiview:          {} (max {} views)",
        yes(f.multiview),
        l.max_multiview_view_count
    );
    crate::say!(
        "    geometry shader:    {} (max {} output vertices, {} invocations)",
        yes(f.geometry_shader),
        l.max_geometry_output_vertices,
        l.max_geometry_shader_invocations
    );
    crate::say!("    shaderOutputLayer:  {}", yes(f.shader_output_layer));
    crate::say!(
        "    mesh shader:        {} (max {} output layers)",
        yes(f.mesh_shader),
        l.max_mesh_output_layers
    );
    crate::say!("    ray query:          {}", yes(f.ray_query));
    crate::say!("    timestamps:         {}", yes(f.timestamps));
    crate::say!("    pipeline stats:     {}", yes(f.pipeline_statistics));
    crate::say!("    anisotropy:         {}", yes(f.sampler_anisotropy));
}
