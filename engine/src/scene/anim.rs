//! TEMPORARY stub (replaced by the scene-loader branch).
use glam::Vec3;
#[derive(Debug, Clone, PartialEq)]
pub enum Animation {
    Orbit {
        center: Vec3,
        axis: Vec3,
        period_s: f32,
    },
}
impl Animation {
    pub fn position_at(&self, base: Vec3, t_s: f64) -> Vec3 {
        match self {
            Animation::Orbit {
                center,
                axis,
                period_s,
            } => {
                let a = (std::f64::consts::TAU * t_s / f64::from(*period_s)) as f32;
                *center + glam::Quat::from_axis_angle(axis.normalize(), a) * (base - *center)
            }
        }
    }
}
