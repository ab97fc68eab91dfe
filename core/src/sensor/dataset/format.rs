//! How a dataset is written (`--format`): its frame folders (`files`), a ROS 2 bag (`mcap`,
//! `sensor::bag`), or both. The bag is made from the frames, so a run renders them either way;
//! with `mcap` alone they are not kept in the output.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

/// The forms a dataset is written in: at least one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Format {
    pub files: bool,
    pub mcap: bool,
}

impl Default for Format {
    fn default() -> Self {
        Self {
            files: true,
            mcap: false,
        }
    }
}

const NAMES: &str = "files, mcap, or both comma-separated";

impl FromStr for Format {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let mut f = Format {
            files: false,
            mcap: false,
        };
        for word in text.split(',').map(str::trim) {
            let slot = match word {
                "files" => &mut f.files,
                "mcap" => &mut f.mcap,
                "" => {
                    return Err(format!(
                        "`{text}`: an empty format name; the formats: {NAMES}"
                    ))
                }
                other => return Err(format!("`{other}` is not a format: {NAMES}")),
            };
            if *slot {
                return Err(format!("`{word}` is named twice"));
            }
            *slot = true;
        }
        Ok(f)
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.names().join(","))
    }
}

impl Format {
    fn names(&self) -> Vec<&'static str> {
        let mut names = Vec::new();
        if self.files {
            names.push("files");
        }
        if self.mcap {
            names.push("mcap");
        }
        names
    }
}

impl Serialize for Format {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.names().serialize(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_once_each_and_print_back() {
        let both: Format = "mcap, files".parse().unwrap();
        assert_eq!((both.files, both.mcap), (true, true));
        assert_eq!(both.to_string(), "files,mcap");
        assert_eq!("mcap".parse::<Format>().unwrap().to_string(), "mcap");
        assert_eq!(Format::default().to_string(), "files");
        let e = "files,bag".parse::<Format>().unwrap_err();
        assert_eq!(
            e,
            "`bag` is not a format: files, mcap, or both comma-separated"
        );
        assert_eq!(
            "mcap,mcap".parse::<Format>().unwrap_err(),
            "`mcap` is named twice"
        );
        assert!(""
            .parse::<Format>()
            .unwrap_err()
            .contains("empty format name"));
    }
}
