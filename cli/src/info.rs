//! `specchio info`: every Vulkan device, what it supports, and which one would be used.

use std::process::ExitCode;

use anyhow::Result;
use specchio::render::lookups;
use specchio::render::methods::Method;
use specchio::scene::Lookup;
use specchio::vk::device::{self, DeviceInfo, MIN_MESA_MAJOR};

use crate::records::{InfoDevice, InfoLookup, InfoMethod, InfoRecord};
use specchio::process::probe;
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
    specchio::process::validation::checked(&log, listed)
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
        specchio::say!("{}", serde_json::to_string_pretty(&InfoRecord { devices })?);
        return Ok(ExitCode::SUCCESS);
    }
    if candidates.is_empty() {
        specchio::say!("no Vulkan device found (Debian: apt-get install mesa-vulkan-drivers)");
    }
    for (c, ms) in candidates.iter().zip(&methods) {
        print_device(
            &c.info,
            c.rejected.as_deref(),
            default == Some(c.info.index),
        );
        for (m, r) in ms {
            match r {
                Ok(()) => specchio::say!("    method {:<20} usable", m.name()),
                Err(why) => specchio::say!("    method {:<20} NOT USABLE: {why}", m.name()),
            }
        }
        for (l, why) in lookup_support(c) {
            match why {
                None => specchio::say!("    lookup {:<20} usable", l.name()),
                Some(why) => specchio::say!("    lookup {:<20} NOT USABLE: {why}", l.name()),
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
    specchio::say!("[{}] {} ({}){mark}", i.index, i.name, i.device_type);
    specchio::say!("    --device:           {} (or {})", i.short_name, i.index);
    match rejected {
        Some(why) => specchio::say!("    status:             NOT USABLE: {why}"),
        None => specchio::say!("    status:             usable"),
    }
    specchio::say!(
        "    driver:             {} {} (version {})",
        i.driver_name,
        i.driver_info,
        i.driver_version
    );
    specchio::say!("    Vulkan:             {}", i.api_version);
    if mesa_too_old(i) {
        specchio::say!("    WARNING:            Mesa {} is older than {MIN_MESA_MAJOR}; results may differ (see README)",
            i.mesa_version.as_deref().unwrap_or("?"));
    }
    let l = &i.limits;
    let f = &i.features;
    specchio::say!("    limits:             cube {} px, 2D {} px, {} layers, {} B push constants, anisotropy {}x, timestamp {} ns",
        l.max_image_dimension_cube, l.max_image_dimension_2d, l.max_image_array_layers,
        l.max_push_constants_size, l.max_sampler_anisotropy, l.timestamp_period_ns);
    specchio::say!(
        "    memory:             {} per allocation, {} device-local heap",
        specchio::render::budget::bytes_text(l.max_memory_allocation_bytes),
        specchio::render::budget::bytes_text(l.device_local_heap_bytes)
    );
    specchio::say!(
        "    multiview:          {} (max {} views)",
        yes(f.multiview),
        l.max_multiview_view_count
    );
    specchio::say!(
        "    geometry shader:    {} (max {} output vertices, {} invocations)",
        yes(f.geometry_shader),
        l.max_geometry_output_vertices,
        l.max_geometry_shader_invocations
    );
    specchio::say!("    shaderOutputLayer:  {}", yes(f.shader_output_layer));
    specchio::say!(
        "    mesh shader:        {} (max {} output layers)",
        yes(f.mesh_shader),
        l.max_mesh_output_layers
    );
    specchio::say!("    ray query:          {}", yes(f.ray_query));
    specchio::say!("    timestamps:         {}", yes(f.timestamps));
    specchio::say!("    pipeline stats:     {}", yes(f.pipeline_statistics));
    specchio::say!("    anisotropy:         {}", yes(f.sampler_anisotropy));
}
