//! Running the `specchio` binary as a user does: validation on, and whatever it says held
//! to readable numbers ([`readable_numbers`]).

/// The `specchio` binary: only the CLI crate's tests (tests/cli/) have it, so the engine's
/// tests, which share this module, compile without it and never call this.
pub(super) fn binary() -> &'static str {
    match option_env!("CARGO_BIN_EXE_specchio") {
        Some(path) => path,
        None => panic!("only the tests in tests/cli/ have the specchio binary to run"),
    }
}

/// Runs the `specchio` binary with `args`, validation on. Whatever it says is held to
/// [`readable_numbers`].
pub fn specchio(args: &[&str]) -> std::process::Output {
    specchio_with(args, &[])
}

/// [`specchio`] with more environment variables.
pub fn specchio_with(args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    let out = std::process::Command::new(binary())
        .args(args)
        .env("SPECCHIO_VALIDATE", "1")
        .envs(env.iter().copied())
        .output()
        .expect("the specchio binary runs");
    readable_numbers(args, &out);
    out
}

/// The environment that makes a command say its estimate after its first part, on a machine
/// of any speed (`process::progress`).
pub const ESTIMATE_AT_ONCE: (&str, &str) = ("SPECCHIO_ESTIMATE_AFTER_S", "0");

/// The estimate line in `stderr` for the work named `what`, checked to name its whole
/// (`total` `unit`s), the part done and the time left.
pub fn estimate_line<'a>(stderr: &'a str, what: &str, total: u64, unit: &str) -> &'a str {
    let line = stderr
        .lines()
        .find(|l| l.starts_with(&format!("{what}: ")))
        .unwrap_or_else(|| panic!("no estimate for `{what}`:\n{stderr}"));
    assert!(
        line.contains(&format!(" of {total} {unit} in ")) && line.contains(" left"),
        "{line}"
    );
    line
}

/// The most digits in a row a message may print. An f64 needs 17 significant digits and a
/// u64 20; a longer run is a float printed with Rust's `{}`, which never switches to an
/// exponent (`1e-310` comes out as a 0 and 309 more digits): every message must print its
/// numbers through `specchio::text::num_text`.
pub const MAX_DIGITS_IN_A_ROW: usize = 24;

/// Fails when the command's stderr, or its stdout where that is text, holds a run of more
/// than [`MAX_DIGITS_IN_A_ROW`] decimal digits (checked on every run of the binary through
/// these helpers, so the rule holds for every message those runs provoke; an image written
/// to stdout is bytes, not text, and is left alone). A hexadecimal word (a staging folder's
/// 32 random hex digits, which may hold 25 decimal ones in a row) is a name, not a number.
pub fn readable_numbers(args: &[&str], out: &std::process::Output) {
    let streams = [("stderr", &out.stderr), ("stdout", &out.stdout)];
    for (stream, bytes) in streams {
        if let Ok(text) = std::str::from_utf8(bytes) {
            readable_text(args, stream, text);
        }
    }
}

/// [`readable_numbers`] of text the command said on `stream` (a test that reads a running
/// command's stderr as it comes).
pub fn readable_text(args: &[&str], stream: &str, text: &str) {
    let longest = text
        .split(|c: char| !c.is_ascii_hexdigit())
        .filter(|word| word.chars().all(|c| c.is_ascii_digit()))
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(
        longest <= MAX_DIGITS_IN_A_ROW,
        "specchio {args:?}: its {stream} prints a number of {longest} digits in a row:\n{text}"
    );
}

/// Runs `command` (the specchio binary as a test set it up: its environment, its folder, its
/// streams) to its end; whatever it says is held to [`readable_numbers`], as every run
/// through these helpers is.
pub fn output_of(command: &mut std::process::Command) -> std::process::Output {
    let out = command.output().expect("the command runs");
    readable_numbers(&args_of(command), &out);
    out
}

/// `command`'s arguments, for messages.
pub fn args_of(command: &std::process::Command) -> Vec<&str> {
    (command.get_args())
        .map(|a| a.to_str().unwrap_or("(not UTF-8)"))
        .collect()
}

/// Runs `specchio ARGS`, validation on; one still running after `patience` is killed and
/// reported (the point is to fail rather than hang the suite when a read blocks).
pub fn specchio_within(args: &[&str], patience: std::time::Duration) -> std::process::Output {
    use std::process::Stdio;
    let mut child = std::process::Command::new(binary())
        .args(args)
        .env("SPECCHIO_VALIDATE", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the specchio binary runs");
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > patience {
            child.kill().unwrap();
            panic!("specchio {args:?}: still running after {patience:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    readable_numbers(args, &out);
    out
}

/// What a running child says on stderr, read as it comes: a thread drains the pipe (so the
/// child never blocks on it) into a string a test can watch while the child runs.
pub struct Stderr {
    said: std::sync::Arc<std::sync::Mutex<String>>,
    reader: std::thread::JoinHandle<()>,
}

impl Stderr {
    /// `child`'s stderr, which must be piped.
    pub fn of(child: &mut std::process::Child) -> Self {
        use std::io::Read;
        let mut stderr = child.stderr.take().expect("stderr piped");
        let said = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
        let into = said.clone();
        let reader = std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = stderr.read(&mut buf) {
                if n == 0 {
                    break;
                }
                let text = String::from_utf8_lossy(&buf[..n]);
                into.lock().unwrap().push_str(&text);
            }
        });
        Self { said, reader }
    }

    /// Whether it has said `text` yet.
    pub fn contains(&self, text: &str) -> bool {
        self.said.lock().unwrap().contains(text)
    }

    /// Everything it said, once the child has closed the pipe.
    pub fn all(self) -> String {
        self.reader.join().unwrap();
        self.said.lock().unwrap().clone()
    }
}

/// Runs the `specchio` binary with `args`, its estimate said after the first part
/// ([`ESTIMATE_AT_ONCE`]), and sends it Ctrl-C once a stderr line starts with `estimate`. Its
/// output, what it said on stderr (held to readable numbers) and that line.
pub fn interrupted_after_estimate(
    args: &[&str],
    estimate: &str,
) -> (std::process::Output, String, String) {
    let mut child = std::process::Command::new(binary())
        .args(args)
        .env(ESTIMATE_AT_ONCE.0, ESTIMATE_AT_ONCE.1)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the specchio binary runs");
    let stderr = Stderr::of(&mut child);
    let result = super::signal_when(child, libc::SIGINT, "the estimate", || {
        stderr.contains(estimate)
    });
    let said = stderr.all();
    readable_text(&[args[0], "(stopped)"], "stderr", &said);
    let line = (said.lines().find(|l| l.starts_with(estimate)))
        .unwrap_or_else(|| panic!("no line starting {estimate:?}:\n{said}"))
        .to_owned();
    (result, said, line)
}
