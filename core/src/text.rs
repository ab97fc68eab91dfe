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

/// A time in seconds for a message: milliseconds in the everyday range, scientific notation
/// outside it.
pub fn time_text(t: f64) -> String {
    if t == 0.0 || (1e-3..1e9).contains(&t.abs()) {
        format!("{t:.3}")
    } else {
        format!("{t:.3e}")
    }
}
