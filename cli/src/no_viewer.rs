//! `specchio view` in a build without the viewer (`--no-default-features`, as the main job,
//! scripts/run.sh, builds to answer sooner): the command is still there, takes whatever the
//! viewer would, and says how to build the viewer instead of failing as an unknown command.

use std::ffi::OsString;
use std::process::ExitCode;

// Whatever the viewer's own arguments would be, `--help` included (it answers with the same
// sentence): none are read.
#[derive(clap::Args, Debug)]
#[command(disable_help_flag = true)]
pub struct Args {
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0.., hide = true)]
    pub ignored: Vec<OsString>,
}

/// The one-line answer: what is missing, why, and the command that adds it.
pub const MISSING: &str = "this specchio was built without the viewer (the main job, \
    scripts/run.sh, leaves it out to answer sooner): build it with `cargo build --release \
    -p specchio-cli`, then run `target/release/specchio view` again (docs/viewer.md)";

pub fn run(_: &Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!(MISSING)
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    /// `specchio view` as a build without the viewer parses it.
    #[derive(Parser)]
    struct Cli {
        #[command(subcommand)]
        command: Command,
    }

    #[derive(clap::Subcommand)]
    enum Command {
        View(super::Args),
    }

    /// Any view command line (the scene, options, values that look like options) is taken,
    /// and running it fails with the sentence that names the build command.
    #[test]
    fn a_view_without_the_viewer_says_how_to_build_it() {
        for line in [
            &["specchio", "view"][..],
            &["specchio", "view", "scenes/thesis-room.toml"],
            &[
                "specchio",
                "view",
                "scenes/thesis-room.toml",
                "--frames",
                "3",
                "--keys",
                "-,w",
            ],
            &["specchio", "view", "--help"],
        ] {
            let Cli {
                command: Command::View(args),
            } = Cli::try_parse_from(line).unwrap_or_else(|e| panic!("{line:?}: {e}"));
            let err = super::run(&args).unwrap_err().to_string();
            assert!(
                err.contains("cargo build --release -p specchio-cli"),
                "{err}"
            );
            assert!(err.contains("without the viewer"), "{err}");
        }
    }
}
