//! Numbers and times written for people: every message that names a value uses these, so a
//! value reads the same in the scene loader's errors as in the mirror shapes'.

/// A number for a message: plain digits in the everyday range, scientific notation outside it
/// (`1e-310`, not a 0 followed by 300 digits; `3.4028235e38`, not 39 digits). f32 values print
/// as f32 (shortest digits that read back to the same f32).
pub fn num_text<T: NumText>(v: T) -> String {
    v.text()
}

/// The length of an f32 vector for a message: summed in f64, so that one of `[1e30, 0, 0]`
/// does not overflow to "inf", and said as an f32 where it is one (`1e30`, not its f64
/// expansion).
pub fn length_text(v: glam::Vec3) -> String {
    let length = v.as_dvec3().length();
    match length <= f64::from(f32::MAX) {
        true => num_text(length as f32),
        false => num_text(length),
    }
}

/// A computed number for a message, to four significant digits (`40.13`, not
/// `40.132545912730585`): a value the program worked out, not one the user gave, which
/// [`num_text`] repeats exactly.
pub fn approx_text(v: f64) -> String {
    match format!("{v:.3e}").parse::<f64>() {
        Ok(rounded) if v.is_finite() => num_text(rounded),
        _ => num_text(v),
    }
}

pub trait NumText {
    fn text(self) -> String;
}

macro_rules! num_text_for {
    ($t:ty) => {
        impl NumText for $t {
            fn text(self) -> String {
                if self == 0.0 || !self.is_finite() || (1e-4..1e9).contains(&self.abs()) {
                    format!("{self}")
                } else {
                    format!("{self:e}")
                }
            }
        }
    };
}
num_text_for!(f32);
num_text_for!(f64);

/// A count for a message. One computed with saturating arithmetic (a grid of a spacing near
/// the smallest float) stops at `u64::MAX`: it says "more than 1.8e19" instead of twenty
/// digits that are not the count.
pub fn count_text(n: u64) -> String {
    match n {
        u64::MAX => "more than 1.8e19".to_owned(),
        n => n.to_string(),
    }
}

/// A user's text quoted in a message, shortened to its first 60 characters (and how many it
/// left out) so that a corrupt line or a 100,000-character value cannot flood the terminal;
/// quoted and escaped as Rust's `{:?}` does, so control characters show.
pub fn quoted_text(text: &str) -> String {
    const MAX: usize = 60;
    match text.char_indices().nth(MAX) {
        Some((i, _)) => format!(
            "{:?}... ({} more characters)",
            &text[..i],
            text[i..].chars().count()
        ),
        None => format!("{text:?}"),
    }
}

/// The longest run of characters without a space a message keeps whole: a path's length
/// (Linux allows 4,096 bytes, but no real one comes near); a longer run is a value copied
/// from a corrupt or hostile input.
const MAX_WORD: usize = 512;
/// The most characters a message keeps (an error that lists a scene's names, one after another).
const MAX_MESSAGE: usize = 4096;

/// An error message bounded for a terminal, whatever an input put into it: a run of more than
/// [`MAX_WORD`] characters without a space keeps its first 60 and says how many it left out,
/// and a message of more than [`MAX_MESSAGE`] characters keeps its start and says the same.
/// Every message the commands and Python say as an error goes through here.
pub fn bounded_message(text: &str) -> String {
    let left_out = |n: usize| format!("... ({n} more characters)");
    let mut out = String::with_capacity(text.len().min(MAX_MESSAGE + 64));
    for (i, word) in text.split(' ').enumerate() {
        if i > 0 {
            out.push(' ');
        }
        let chars = word.chars().count();
        match chars > MAX_WORD {
            true => {
                out.extend(word.chars().take(60));
                out.push_str(&left_out(chars - 60));
            }
            false => out.push_str(word),
        }
    }
    let chars = out.chars().count();
    if chars > MAX_MESSAGE {
        let keep = MAX_MESSAGE - 64;
        let cut: String = out.chars().take(keep).collect();
        return cut + &left_out(chars - keep);
    }
    out
}

/// A time in seconds for a message: milliseconds in the everyday range, scientific notation
/// outside it.
pub fn time_text(t: f64) -> String {
    if t == 0.0 || (1e-3..1e9).contains(&t.abs()) {
        format!("{t:.3}")
    } else {
        format!("{t:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A computed value reads to four significant digits, in the everyday range or outside it.
    #[test]
    fn a_computed_value_reads_to_four_digits() {
        assert_eq!(approx_text(40.132545912730585), "40.13");
        assert_eq!(approx_text(4.999995), "5");
        assert_eq!(approx_text(-2.5e-7), "-2.5e-7");
        assert_eq!(approx_text(f64::INFINITY), "inf");
    }

    /// A message of everyday words and paths is kept as it is; a 100,000-character value keeps
    /// its first 60 and says how many it left out; a long list stops at its bound.
    #[test]
    fn a_message_is_bounded_whatever_its_input() {
        let plain = "scene.toml:3:9: mirror.lookup: unknown variant `boxx`, expected `box`";
        assert_eq!(bounded_message(plain), plain);
        let path = format!("/{}/a.toml: not found", "d".repeat(400));
        assert_eq!(bounded_message(&path), path);
        let flood = format!("mirror.lookup: unknown variant `{}`", "x".repeat(100_000));
        let said = bounded_message(&flood);
        assert!(said.len() < 200, "{said}");
        assert!(said.ends_with("... (99942 more characters)"), "{said}");
        let list = format!("defined: {}", vec!["wall"; 10_000].join(", "));
        let said = bounded_message(&list);
        assert!(said.chars().count() < MAX_MESSAGE + 64, "{}", said.len());
        assert!(said.starts_with("defined: wall, wall") && said.ends_with("more characters)"));
    }

    /// A quoted value is escaped and at most 60 characters of its own.
    #[test]
    fn a_quoted_value_is_short_and_escaped() {
        assert_eq!(quoted_text("bvh8"), "\"bvh8\"");
        assert_eq!(quoted_text("a\u{7}b"), "\"a\\u{7}b\"");
        let long = format!("{:?}... (940 more characters)", "y".repeat(60));
        assert_eq!(quoted_text(&"y".repeat(1000)), long);
    }
}
