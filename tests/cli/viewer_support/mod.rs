//! What the viewer's window tests share: display servers to run `specchio view` on (Xvfb,
//! headless weston), a viewer kept running while a test drives it, and image comparisons.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::{self, root, temp_dir, Scratch};

mod pixels;
// Not every test binary reads the window's pixels.
#[allow(unused_imports)]
pub use pixels::*;

/// A private X server on a free display number, stopped on drop.
pub struct Xvfb {
    child: Child,
    pub display: String,
}

impl Xvfb {
    /// Starts one, or `None` (with the reason printed) when Xvfb is not installed.
    pub fn start() -> Option<Self> {
        if Command::new("Xvfb").arg("-help").output().is_err() {
            missing("Xvfb", "apt-get install xvfb; scripts/setup.sh does");
            return None;
        }
        // A display number of this process's own, away from common ones (0..10), and of
        // this test's own: tests run in parallel threads of one process, and two that
        // checked the same free number before either server took it would share a server
        // (the first to finish would stop it under the other).
        static STARTED: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let own = STARTED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let first = 100 + (std::process::id() % 400) * 2 + own * 1000;
        for n in (first..).step_by(7).take(50) {
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
                || Path::new(&format!("/tmp/.X{n}-lock")).exists()
            {
                continue;
            }
            let display = format!(":{n}");
            let mut child = Command::new("Xvfb")
                // -noreset: by default the server resets when its last client leaves, and a
                // viewer connecting during that reset fails ("cannot connect to the display").
                .args([
                    &display,
                    "-screen",
                    "0",
                    "1920x1080x24",
                    "-nolisten",
                    "tcp",
                    "-noreset",
                ])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("Xvfb starts");
            // Ready when its socket accepts a connection: the socket file alone can exist
            // before the server serves it, or belong to a server that then failed (a number
            // another process took meanwhile), in which case the next number is tried.
            let socket = format!("/tmp/.X11-unix/X{n}");
            let start = Instant::now();
            let mut exited = false;
            while start.elapsed() < Duration::from_secs(10) {
                if std::os::unix::net::UnixStream::connect(&socket).is_ok() {
                    return Some(Self { child, display });
                }
                if child.try_wait().ok().flatten().is_some() {
                    exited = true;
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
            assert!(exited, "Xvfb {display} did not accept connections in 10 s");
        }
        panic!("no free X display number");
    }
}

/// A display server the viewer can be started on.
pub trait Display {
    /// `specchio view ARGS` on this display, validation on.
    fn command(&self, args: &[&str]) -> Command;

    fn view(&self, args: &[&str]) -> Output {
        self.command(args).output().expect("specchio view runs")
    }
}

impl Display for Xvfb {
    fn command(&self, args: &[&str]) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_specchio"));
        c.arg("view")
            .args(args)
            .env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("SPECCHIO_VALIDATE", "1");
        c
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

pub fn ok(output: &Output, what: &str) {
    assert!(
        output.status.success(),
        "{what}: {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status,
        text(&output.stdout),
        text(&output.stderr)
    );
}

/// An RGB8 image from a PNG file: (width, height, bytes).
pub fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// The largest channel difference and how many channels differ at all.
pub fn difference(a: &Path, b: &Path) -> (u8, usize) {
    let (wa, ha, pa) = read_png(a);
    let (wb, hb, pb) = read_png(b);
    assert_eq!((wa, ha), (wb, hb), "{} vs {}", a.display(), b.display());
    let diffs = pa.iter().zip(&pb).map(|(x, y)| x.abs_diff(*y));
    diffs.fold((0, 0), |(max, n), d| (max.max(d), n + usize::from(d > 0)))
}

/// The viewer's screenshot equals the render's image within the stated tolerance (one
/// 8-bit code, see the module comment).
pub fn assert_same_image(shot: &Path, rendered: &Path) {
    let (max, n) = difference(shot, rendered);
    println!(
        "{} vs {}: max difference {max}, {n} channels differ",
        shot.display(),
        rendered.display()
    );
    assert!(
        max <= 1,
        "{} differs from {} by up to {max}",
        shot.display(),
        rendered.display()
    );
}

/// `specchio render SCENE --frame F` into a fresh folder.
pub fn render(scene: &Path, frame: u32, name: &str) -> Scratch {
    render_with(scene, frame, name, &[])
}

/// [`render`] with more arguments (`--device swiftshader`).
pub fn render_with(scene: &Path, frame: u32, name: &str, extra: &[&str]) -> Scratch {
    let out = temp_dir(name);
    let frame = frame.to_string();
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--frame",
        &frame,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let result = common::specchio(&args);
    ok(&result, "specchio render");
    out
}

pub fn thesis_room() -> PathBuf {
    root().join("scenes/thesis-room.toml")
}

/// The last `NAME: x y w h` line the viewer printed (the menu's or the help's rectangle in
/// window pixels).
pub fn reported_rect(stdout: &str, name: &str) -> [u32; 4] {
    let line = stdout
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix(&format!("{name}: ")))
        .unwrap_or_else(|| panic!("no `{name}:` line in\n{stdout}"));
    let v: Vec<u32> = line.split(' ').map(|n| n.parse().unwrap()).collect();
    [v[0], v[1], v[2], v[3]]
}

/// Channels that differ inside and outside `rect`.
pub fn differences_around(a: &Path, b: &Path, [x, y, w, h]: [u32; 4]) -> (usize, usize) {
    let (wa, ha, pa) = read_png(a);
    let (wb, hb, pb) = read_png(b);
    assert_eq!((wa, ha), (wb, hb));
    let (mut inside, mut outside) = (0, 0);
    for (i, (p, q)) in pa.chunks_exact(3).zip(pb.chunks_exact(3)).enumerate() {
        let (px, py) = (i as u32 % wa, i as u32 / wa);
        let within = (x..x + w).contains(&px) && (y..y + h).contains(&py);
        let n = p.iter().zip(q).filter(|(u, v)| u != v).count();
        if within {
            inside += n;
        } else {
            outside += n;
        }
    }
    (inside, outside)
}

/// `specchio view thesis-room --keys KEYS --frames 3 --screenshot FILE`: (file, stdout).
pub fn shot_with_keys(x: &impl Display, keys: &str, name: &str) -> (Scratch, String) {
    let shot = temp_dir(name);
    let out = x.view(&[
        thesis_room().to_str().unwrap(),
        "--keys",
        keys,
        "--frames",
        "3",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    ok(&out, "specchio view");
    (shot, text(&out.stdout))
}

/// A window test cannot check anything without `tool`: a [`common::skip`].
fn missing(tool: &str, install: &str) {
    common::skip(
        "the window test",
        &format!("{tool} is not installed ({install})"),
    );
}

/// A private headless Wayland compositor (weston's headless backend), stopped on drop. It
/// listens in a runtime folder of its own (0700, as Wayland asks of XDG_RUNTIME_DIR).
pub struct Weston {
    child: Child,
    // Removed when the compositor is (fields drop after `Drop::drop` has stopped it).
    runtime_dir: Scratch,
    socket: String,
}

impl Weston {
    /// Starts one, or `None` (with the reason printed) when weston is not installed.
    pub fn start(name: &str) -> Option<Self> {
        if Command::new("weston").arg("--version").output().is_err() {
            missing("weston", "apt-get install weston; scripts/setup.sh does");
            return None;
        }
        use std::os::unix::fs::PermissionsExt;
        let runtime_dir = temp_dir(&format!("{name}-xdg"));
        std::fs::create_dir_all(&runtime_dir).unwrap();
        std::fs::set_permissions(&runtime_dir, std::fs::Permissions::from_mode(0o700)).unwrap();
        let socket = format!("specchio-{name}");
        // No renderer (the headless default): the compositor still takes the buffers and
        // answers frame callbacks, and the test reads the swapchain image, not the screen.
        let child = Command::new("weston")
            .args([
                "--backend=headless-backend.so",
                &format!("--socket={socket}"),
                "--idle-time=0",
                "--no-config",
                "--width=1920",
                "--height=1080",
            ])
            .env("XDG_RUNTIME_DIR", &runtime_dir)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("weston starts");
        let path = runtime_dir.join(&socket);
        let start = Instant::now();
        while !path.exists() && start.elapsed() < Duration::from_secs(20) {
            std::thread::sleep(Duration::from_millis(50));
        }
        assert!(path.exists(), "weston did not open {}", path.display());
        Some(Self {
            child,
            runtime_dir,
            socket,
        })
    }
}

impl Weston {
    /// Stops the compositor now, as a crash would (SIGKILL), under any client it has.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Display for Weston {
    fn command(&self, args: &[&str]) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_specchio"));
        c.arg("view")
            .args(args)
            .env("WAYLAND_DISPLAY", &self.socket)
            .env("XDG_RUNTIME_DIR", &self.runtime_dir)
            .env_remove("DISPLAY")
            .env("SPECCHIO_VALIDATE", "1");
        c
    }
}

impl Drop for Weston {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `true` when xdotool can be run (it is what sends keys and clicks under Xvfb).
pub fn has_xdotool() -> bool {
    if Command::new("xdotool").arg("version").output().is_err() {
        missing("xdotool", "scripts/setup.sh installs it");
        return false;
    }
    true
}

/// The openbox window manager on an X server, stopped on drop: what minimises a window as a
/// desktop does (unmapped, `_NET_WM_STATE_HIDDEN` set). `None` (the reason printed) when it
/// is not installed.
pub struct Openbox(Child);

impl Openbox {
    pub fn start(x: &Xvfb) -> Option<Self> {
        let Ok(child) = Command::new("openbox")
            .env("DISPLAY", &x.display)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
        else {
            missing("openbox", "scripts/setup.sh installs it");
            return None;
        };
        let manager = Self(child);
        // Managing once a window of its own (class "openbox") exists.
        let start = Instant::now();
        while xdotool_may_fail(x, &["search", "--class", "openbox"]).is_empty() {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "openbox did not start"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
        Some(manager)
    }
}

impl Drop for Openbox {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `xdotool ARGS` on `x`'s display, its stdout (empty when it failed: `search` with no match).
fn xdotool_may_fail(x: &Xvfb, args: &[&str]) -> String {
    let out = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", &x.display)
        .output()
        .unwrap();
    text(&out.stdout)
}

/// A viewer left running while a test drives it, its stdout read line by line as it comes
/// and its stderr read as it comes too (a pipe nobody reads fills up, and the viewer's next
/// message would then block it for good).
pub struct Running {
    child: Child,
    lines: std::sync::mpsc::Receiver<String>,
    reader: std::thread::JoinHandle<String>,
    errors: std::thread::JoinHandle<Vec<u8>>,
}

impl Running {
    pub fn spawn(display: &impl Display, args: &[&str]) -> Self {
        Self::spawn_command(display.command(args))
    }

    /// [`Running::spawn`] with a variable set (a fault to inject).
    pub fn spawn_with_var(display: &impl Display, args: &[&str], var: (&str, &str)) -> Self {
        let mut command = display.command(args);
        command.env(var.0, var.1);
        Self::spawn_command(command)
    }

    /// [`Running::spawn`] with `folder` as the viewer's current folder.
    pub fn spawn_in(display: &impl Display, args: &[&str], folder: &Path) -> Self {
        let mut command = display.command(args);
        command.current_dir(folder);
        Self::spawn_command(command)
    }

    fn spawn_command(mut command: Command) -> Self {
        let mut child = command
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (sender, lines) = std::sync::mpsc::channel();
        let mut stderr = child.stderr.take().unwrap();
        let errors = std::thread::spawn(move || {
            let mut all = Vec::new();
            let _ = std::io::Read::read_to_end(&mut stderr, &mut all);
            all
        });
        let stdout = child.stdout.take().unwrap();
        let reader = std::thread::spawn(move || {
            use std::io::BufRead;
            let mut all = String::new();
            for line in std::io::BufReader::new(stdout)
                .lines()
                .map_while(Result::ok)
            {
                all.push_str(&line);
                all.push('\n');
                let _ = sender.send(line);
            }
            all
        });
        Self {
            child,
            lines,
            reader,
            errors,
        }
    }

    /// The CPU time the viewer has used so far, in the kernel's clock ticks (user and system,
    /// fields 14 and 15 of `/proc/PID/stat`): for ratios of two stretches of one run.
    pub fn cpu_ticks(&self) -> u64 {
        let stat = std::fs::read_to_string(format!("/proc/{}/stat", self.child.id()))
            .expect("the viewer's /proc stat");
        let (_, state, ticks) = parse_stat(&stat).expect("a stat line");
        ticks.unwrap_or_else(|| panic!("CPU ticks in the viewer's stat ({state}): {stat}"))
    }

    /// The viewer's threads, one a line: name, state (R running, S sleeping, D in the
    /// kernel), CPU ticks used (user and system) and the kernel function it waits in: what a
    /// failure reports to tell a stuck viewer from a slow one.
    pub fn threads(&self) -> String {
        let tasks = format!("/proc/{}/task", self.child.id());
        let Ok(entries) = std::fs::read_dir(&tasks) else {
            return format!("{tasks}: gone");
        };
        let mut lines: Vec<String> = entries
            .filter_map(Result::ok)
            .map(|e| {
                let stat = std::fs::read_to_string(e.path().join("stat")).unwrap_or_default();
                let wchan = std::fs::read_to_string(e.path().join("wchan")).unwrap_or_default();
                let Some((name, state, ticks)) = parse_stat(&stat) else {
                    return format!("{:?}: no stat", e.file_name());
                };
                format!("{name} {state} ticks {} in {wchan}", ticks.unwrap_or(0))
            })
            .collect();
        lines.sort();
        lines.join("\n")
    }

    /// Waits (at most two minutes) for a line starting with `what`, and returns it.
    pub fn wait_for(&self, what: &str) -> String {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(120) {
            match self.lines.recv_timeout(Duration::from_secs(1)) {
                Ok(line) if line.starts_with(what) => return line,
                Ok(_) | Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(_) => break,
            }
        }
        panic!("the viewer never printed `{what}`");
    }

    /// Waits (at most a minute) for the viewer to exit by itself; requires success and
    /// returns all it printed.
    pub fn finish(self) -> String {
        let (out, stdout) = self.exit();
        ok(&out, "specchio view");
        stdout
    }

    /// Waits (at most a minute) for the viewer to exit by itself, however it ends: its exit
    /// status and stderr, and all it printed on stdout. One that does not is killed, and the
    /// failure says what it printed.
    pub fn exit(mut self) -> (Output, String) {
        let start = Instant::now();
        let mut quit = true;
        while self.child.try_wait().unwrap().is_none() {
            if start.elapsed() > Duration::from_secs(60) {
                let _ = self.child.kill();
                quit = false;
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let status = self.child.wait().unwrap();
        let stdout = self.reader.join().unwrap();
        let stderr = self.errors.join().unwrap();
        assert!(
            quit,
            "the viewer did not quit in 60 s (killed)\nstdout:\n{stdout}\nstderr:\n{}",
            text(&stderr)
        );
        let out = Output {
            status,
            stdout: stdout.clone().into_bytes(),
            stderr,
        };
        common::readable_numbers(&["view", "(a running viewer)"], &out);
        (out, stdout)
    }
}

/// A `/proc/.../stat` line's command name, state and CPU ticks (user and system, fields 14
/// and 15). The name (field 2) is in parentheses and may hold spaces: fields are counted
/// after its closing one.
fn parse_stat(stat: &str) -> Option<(&str, &str, Option<u64>)> {
    let (open, close) = stat.find('(').zip(stat.rfind(')'))?;
    let fields: Vec<&str> = stat.get(close + 2..)?.split_whitespace().collect();
    let tick = |i: usize| fields.get(i).and_then(|f| f.parse::<u64>().ok());
    let ticks = tick(11).zip(tick(12)).map(|(user, system)| user + system);
    Some((&stat[open + 1..close], fields.first().copied()?, ticks))
}

/// An Xvfb to drive with xdotool: `None` (the reason printed) when either is missing.
pub fn xvfb_with_xdotool() -> Option<Xvfb> {
    let x = Xvfb::start()?;
    has_xdotool().then_some(x)
}

/// `specchio view ARGS` on `x` (in `folder` when given), once its window has a swapchain,
/// with the window focused for typed keys: the running viewer and the window's id.
pub fn focused_viewer(x: &Xvfb, args: &[&str], folder: Option<&Path>) -> (Running, String) {
    let viewer = match folder {
        Some(folder) => Running::spawn_in(x, args, folder),
        None => Running::spawn(x, args),
    };
    viewer.wait_for("swapchain: ");
    let id = viewer_window(x);
    xdotool(x, &["windowfocus", "--sync", &id]);
    (viewer, id)
}

/// `xdotool ARGS` on `x`'s display, required to succeed; its stdout.
pub fn xdotool(x: &Xvfb, args: &[&str]) -> String {
    let out = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", &x.display)
        .output()
        .unwrap();
    ok(&out, &format!("xdotool {args:?}"));
    text(&out.stdout)
}

/// The id of the viewer's window on `x`.
pub fn viewer_window(x: &Xvfb) -> String {
    let found = xdotool(x, &["search", "--name", "specchio view"]);
    let id = found.lines().next().unwrap_or("").to_owned();
    assert!(!id.is_empty(), "no viewer window");
    id
}
