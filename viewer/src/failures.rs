//! What the window system's failures mean to the viewer: a window destroyed under it, a
//! display that reports it gone, a lost surface. Each ends the viewer cleanly, saying why,
//! instead of a crash.

use std::sync::Arc;

use anyhow::Result;
use winit::event_loop::EventLoop;

use winit::application::ApplicationHandler;

/// Runs the event loop; a panic inside the window system's code becomes an error. winit's X11
/// backend unwraps the replies of a display that reports the window gone: asked the size of
/// a destroyed window, or destroying its input context while an error for an image presented
/// to it is pending, it panics inside `run_app` (`xdotool windowclose` under Xvfb, about one
/// run in five). The viewer's own state is whole (a panic in winit leaves it between two
/// events), so it is torn down as on any error, and the user reads what happened instead of a
/// crash report. The default panic message is held back while the loop runs.
///
/// `window_gone` tells whether the viewer already knew its window was gone (then any panic is
/// that window's); it is set when the panic's message says so.
pub(super) fn run_catching_window_panics<A: ApplicationHandler>(
    event_loop: EventLoop<()>,
    app: &mut A,
    window_gone: impl Fn(&mut A) -> &mut bool,
) -> Result<()> {
    use std::panic::{catch_unwind, set_hook, take_hook, AssertUnwindSafe};
    let caught: Arc<std::sync::Mutex<Option<String>>> = Arc::default();
    let previous = take_hook();
    let held = Arc::clone(&caught);
    set_hook(Box::new(move |info| {
        let place = info
            .location()
            .map_or(String::new(), |l| format!(" at {l}"));
        let message = (info.payload().downcast_ref::<&str>().map(|s| s.to_string()))
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        *held.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{message}{place}"));
    }));
    let ran = catch_unwind(AssertUnwindSafe(|| event_loop.run_app(app)));
    set_hook(previous);
    match ran {
        // winit's only word for a Wayland connection that broke under it (the compositor
        // gone): an exit code. Said for a person, with the display it was.
        Ok(Err(winit::error::EventLoopError::ExitFailure(code))) => Err(anyhow::anyhow!(
            "the display connection broke ({}; the window system's exit code {code}): the \
             compositor or server is gone or ended the connection, and the window with it; \
             start the viewer again once it runs",
            display_name()
        )),
        Ok(result) => Ok(result?),
        Err(_) => {
            let what =
                (caught.lock().unwrap_or_else(|e| e.into_inner()).take()).unwrap_or_default();
            // X's words for a window that no longer exists.
            let gone = what.contains("BadWindow") || what.contains("BadDrawable");
            let known = window_gone(app);
            if *known || gone {
                if !*known {
                    specchio::say!("the window was destroyed from outside ({what}): quitting");
                }
                *known = true;
                return Ok(());
            }
            anyhow::bail!("the window system failed: {what}")
        }
    }
}

/// Whether `e` says the window's surface is gone (`VK_ERROR_SURFACE_LOST_KHR`).
pub(super) fn surface_lost(e: &anyhow::Error) -> bool {
    says(e, ash::vk::Result::ERROR_SURFACE_LOST_KHR)
}

/// Whether `e` says the device is lost (`VK_ERROR_DEVICE_LOST`): nothing more can be drawn,
/// and the viewer ends with a message (the teardown only destroys, which a lost device
/// allows).
pub(super) fn device_lost(e: &anyhow::Error) -> bool {
    says(e, ash::vk::Result::ERROR_DEVICE_LOST)
}

/// Whether one of `e`'s causes is a Vulkan call that answered `result`.
fn says(e: &anyhow::Error, result: ash::vk::Result) -> bool {
    e.chain().any(|cause| {
        matches!(
            cause.downcast_ref::<specchio::vk::GpuError>(),
            Some(specchio::vk::GpuError::Vk { result: r, .. }) if *r == result
        )
    })
}

/// The display the viewer is on, as the environment names it.
fn display_name() -> String {
    match (std::env::var("WAYLAND_DISPLAY"), std::env::var("DISPLAY")) {
        (Ok(w), _) if !w.is_empty() => format!("the Wayland compositor WAYLAND_DISPLAY={w}"),
        (_, Ok(d)) if !d.is_empty() => format!("the X server DISPLAY={d}"),
        _ => "the display".to_owned(),
    }
}

/// On X11: a display connection that breaks (the server gone, the client killed with
/// `xdotool windowkill`) ends the process from Xlib's handler, which cannot return. Xlib's
/// own handler prints its message and calls `exit`, whose exit handlers tear down the
/// driver while the viewer's other threads (the present thread, the driver's own) may be
/// inside it: the process then crashed (SIGSEGV, 3 runs in 8 of the killed-display test). This
/// handler says the same and ends the process with `_exit`: no exit handlers run, and the
/// kernel frees everything (nothing could be torn down through a display that is gone).
pub(super) fn end_cleanly_when_the_display_breaks() {
    let Ok(xlib) = x11_dl::xlib::Xlib::open() else {
        return; // No libX11: winit did not use it either.
    };
    // SAFETY: sets a process-wide function pointer in libX11; the handler is a plain function
    // that never returns.
    unsafe { (xlib.XSetIOErrorHandler)(Some(display_broken)) };
}

/// Xlib's IO error handler (see [`end_cleanly_when_the_display_breaks`]).
unsafe extern "C" fn display_broken(_: *mut x11_dl::xlib::Display) -> std::os::raw::c_int {
    use std::io::Write;
    let display = std::env::var("DISPLAY").unwrap_or_default();
    // Not eprintln!: a closed stderr would panic it, and a panic cannot leave this function.
    let _ = writeln!(
        std::io::stderr(),
        "X connection to {display} broken (the X server or this client's connection is gone): \
         the viewer cannot go on"
    );
    // SAFETY: ends the process at once, as documented above; nothing after it runs.
    unsafe { libc::_exit(1) }
}
