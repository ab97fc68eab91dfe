//! Whether the window can be seen on X11 at all: its map state, asked over a connection of
//! the viewer's own. An unmap sends winit nothing (no `Occluded`, no `Resized`), and
//! without a window manager nothing sets `_NET_WM_STATE_HIDDEN` either, so a window unmapped
//! by a script (`xdotool windowunmap`) or a bare X session was drawn on at full speed
//! (182 % of a core measured). `GetWindowAttributes`' map state answers for every case: a
//! window unmapped, iconified by a window manager (which unmaps it), or inside an unmapped
//! parent is not `Viewable`.

use std::cell::Cell;

use winit::raw_window_handle::{HasWindowHandle, RawWindowHandle};
use winit::window::Window;
use x11rb::connection::Connection;
use x11rb::protocol::xproto::{ConnectionExt, MapState};
use x11rb::rust_connection::RustConnection;

/// A window's map state, asked on demand.
pub struct MapWatch {
    connection: RustConnection,
    window: u32,
    /// The window has been viewable once. Before, it is still being mapped (winit's map
    /// request may not have reached the server when this connection asks): not "hidden".
    shown_once: Cell<bool>,
}

impl MapWatch {
    /// For an X11 window (`None` elsewhere, or when the display cannot be reached a second
    /// time: the viewer then relies on winit's events alone).
    pub fn of(window: &Window) -> Option<Self> {
        let id = match window.window_handle().ok()?.as_raw() {
            RawWindowHandle::Xlib(h) => u32::try_from(h.window).ok()?,
            RawWindowHandle::Xcb(h) => h.window.get(),
            _ => return None,
        };
        // The display winit opened: `DISPLAY` (winit reads nothing else).
        let (connection, _) = x11rb::connect(None).ok()?;
        Some(Self {
            connection,
            window: id,
            shown_once: Cell::new(false),
        })
    }

    /// Whether the window was unmapped after it was first shown (or sits in an unmapped
    /// parent). False when the server does not answer for it (the window is gone: the event
    /// loop hears of that).
    pub fn unmapped(&self) -> bool {
        let reply = (self.connection.get_window_attributes(self.window).ok())
            .and_then(|cookie| cookie.reply().ok());
        let Some(reply) = reply else { return false };
        let viewable = reply.map_state == MapState::VIEWABLE;
        self.shown_once.set(self.shown_once.get() || viewable);
        self.shown_once.get() && !viewable
    }
}

impl Drop for MapWatch {
    fn drop(&mut self) {
        // Nothing of ours lives on the server; the connection closes with the value.
        let _ = self.connection.flush();
    }
}
