//! More of `specchio view`, validation layer on: the viewer on Wayland (a headless weston)
//! shows what `specchio render` writes, as it does under X11; a click on the menu's widget
//! switches the lookup, as the key does; SwiftShader presents there too; and a menu renderer made anew (as a swapchain format
//! change makes one) draws the same menu, font included.
//!
//! Without weston, Xvfb or xdotool the tests that need them print why and pass without
//! checking; scripts/setup.sh installs all three, so CI runs them. The tolerance for
//! comparing with `render`'s PNGs is the one of tests/cli/viewer.rs (one 8-bit code).

#[path = "../common/mod.rs"]
mod common;
mod viewer_support;

use std::time::{Duration, Instant};

use common::temp_dir;
use viewer_support::*;

#[test]
fn on_wayland_both_views_show_what_render_writes() {
    let Some(wayland) = Weston::start("view-wayland") else {
        return;
    };
    let shot = temp_dir("view-wayland.png");
    let out = wayland.view(&[
        thesis_room().to_str().unwrap(),
        "--frames",
        "3",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    ok(&out, "specchio view on Wayland");
    assert!(
        text(&out.stdout).contains("swapchain: 1200x450"),
        "{}",
        text(&out.stdout)
    );
    let rendered = render(&thesis_room(), 2, "view-wayland-render");
    assert_same_image(&shot, &rendered.join("views.png"));
}

/// SwiftShader presents on Wayland (its build crashes only querying an X11 window's surface,
/// where the viewer refuses it: tests/cli/viewer.rs) and shows what `render` on SwiftShader writes.
#[test]
fn on_wayland_swiftshader_shows_what_render_writes_on_it() {
    if !common::devices().iter().any(|d| d == "swiftshader") {
        common::skip("SwiftShader on Wayland", "SwiftShader is not installed");
        return;
    }
    let Some(wayland) = Weston::start("view-wayland-swiftshader") else {
        return;
    };
    let shot = temp_dir("view-wayland-swiftshader.png");
    let out = wayland.view(&[
        thesis_room().to_str().unwrap(),
        "--device",
        "swiftshader",
        "--frames",
        "3",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    ok(&out, "specchio view --device swiftshader on Wayland");
    let device = ["--device", "swiftshader"];
    let rendered = render_with(&thesis_room(), 2, "view-wayland-ss-render", &device);
    assert_same_image(&shot, &rendered.join("views.png"));
}

/// The rectangle of the menu's widget `name` from the viewer's last `widget:` lines.
fn widget(stdout: &str, name: &str) -> [u32; 4] {
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix(&format!("widget: {name} ")))
        .unwrap_or_else(|| panic!("no widget {name} in\n{stdout}"));
    let v: Vec<u32> = line.split(' ').map(|n| n.parse().unwrap()).collect();
    [v[0], v[1], v[2], v[3]]
}

#[test]
fn a_click_on_the_menus_lookup_switches_it() {
    let Some(x) = Xvfb::start() else { return };
    if !has_xdotool() {
        return;
    }
    let viewer = Running::spawn(
        &x,
        &[
            thesis_room().to_str().unwrap(),
            "--keys",
            "f1",
            "--frames",
            "100000",
            "--widgets",
        ],
    );
    // The menu lays itself out the same way for the same window size; the viewer says where
    // each widget is, and the pointer goes to the middle of the `box` lookup's radio button.
    let line = viewer.wait_for("widget: lookup=box ");
    let [bx, by, bw, bh] = widget(&line, "lookup=box");
    let id = viewer_window(&x);
    let title = xdotool(&x, &["getwindowname", &id]);
    assert!(!title.contains(", box, "), "box before the click: {title}");
    let (cx, cy) = ((bx + bw / 2).to_string(), (by + bh / 2).to_string());
    xdotool(&x, &["mousemove", "--window", &id, &cx, &cy]);
    xdotool(&x, &["click", "1"]);
    viewer.wait_for("lookup: box");
    // The window title (refreshed twice a second) names the lookup now drawn.
    let start = Instant::now();
    loop {
        let title = xdotool(&x, &["getwindowname", &id]);
        if title.contains(", box, ") {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the title never named box: {title}"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    xdotool(&x, &["windowfocus", "--sync", &id]);
    xdotool(&x, &["key", "q"]);
    let stdout = viewer.finish();
    assert!(stdout.contains("frames: "), "{stdout}");
    // One switch, to box: the click was taken once and not also as a key.
    assert_eq!(stdout.matches("lookup: ").count(), 1, "{stdout}");
}

/// The menu's first frame is egui's sizing pass, in which nothing takes clicks: its widgets
/// are listed from the second frame on, so a click sent where a listed widget is lands on it
/// (a click sent during the first frame was lost, and the test above failed by chance).
#[test]
fn widgets_are_listed_once_they_take_clicks() {
    let Some(x) = Xvfb::start() else { return };
    let listed = |frames: &str| {
        let out = x.view(&[
            thesis_room().to_str().unwrap(),
            "--keys",
            "f1",
            "--frames",
            frames,
            "--widgets",
        ]);
        ok(&out, "specchio view --widgets");
        text(&out.stdout).matches("widget: ").count()
    };
    assert_eq!(listed("1"), 0, "widgets listed in the sizing pass");
    assert!(
        listed("2") > 10,
        "the menu's widgets are listed in its second frame"
    );
}

#[test]
fn a_new_menu_renderer_draws_the_same_menu() {
    let Some(x) = Xvfb::start() else { return };
    let run = |extra: &[&str], name: &str| {
        let shot = temp_dir(name);
        let mut args = vec![
            thesis_room().to_str().unwrap().to_owned(),
            "--keys".into(),
            "f1".into(),
            "--frames".into(),
            "3".into(),
            "--widgets".into(),
            "--screenshot".into(),
            shot.to_str().unwrap().to_owned(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = x.view(&args);
        ok(&out, "specchio view");
        (shot, text(&out.stdout))
    };
    // --renew-menu-renderer: every frame draws with a renderer that egui never sent its
    // textures to; it has them only through the re-upload of every kept texture.
    let (renewed, stdout) = run(&["--renew-menu-renderer"], "view-renewed.png");
    let (usual, _) = run(&[], "view-renewed-usual.png");
    let [mx, my, mw, _] = reported_rect(&stdout, "menu");
    // The menu down to its buttons' row: below it are the live figures (wall-clock frame
    // times), which differ between any two runs.
    let [_, ry, _, rh] = widget(&stdout, "reset");
    let above_figures = [mx, my, mw, ry + rh - my];
    let (inside, _) = differences_around(&renewed, &usual, above_figures);
    assert_eq!(inside, 0, "the renewed renderer drew the menu differently");
    // Outside: the views and the figures; the views are the same, only figures may differ.
    let [_, _, _, mh] = reported_rect(&stdout, "menu");
    let (_, beyond_menu) = differences_around(&renewed, &usual, [mx, my, mw, mh]);
    assert_eq!(beyond_menu, 0, "pixels outside the menu differ");
}

/// A compositor that dies under the viewer ends it with one line that says so, naming the
/// display, and no panic: it said "Broken pipe (os error 32)" twice, which names nothing.
#[test]
fn a_compositor_that_dies_ends_the_viewer_with_one_message() {
    let Some(mut wayland) = Weston::start("view-wayland-dies") else {
        return;
    };
    let child = wayland
        .command(&[thesis_room().to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(4));
    wayland.kill();
    let start = Instant::now();
    let out = child.wait_with_output().unwrap();
    common::readable_numbers(&["view", "(its compositor killed)"], &out);
    let stderr = text(&out.stderr);
    eprintln!("after {:?}: {:?}\n{stderr}", start.elapsed(), out.status);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("Io error"),
        "{stderr}"
    );
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].contains("Wayland") && errors[0].contains("specchio-view-wayland-dies"),
        "{stderr}"
    );
}
