//! Numbers and times written for people: every message that names a value uses these, so a
//! value reads the same in the scene loader's errors as in the mirror shapes'.

/// A number for a message: plain digits in the everyday range, scientific notation outside it
/// (`1e-310`, not a 0 followed by 300 digits; `3.4028235e38`, not 39 digits). f32 values print
/// as f32 (shortest digits that read back to the same f32).
pub fn num_text<T: NumText>(v: T) -> String {
    v.text()
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

/// A time in seconds for a message: milliseconds in the everyday range, scientific notation
/// outside it.
pub fn time_text(t: f64) -> String {
    if t == 0.0 || (1e-3..1e9).contains(&t.abs()) {
        format!("{t:.3}")
    } else {
        format!("{t:.3e}")
    }
}
