// TEMPORARY stub until the scenario branch is merged.
#[derive(Debug, Clone)]
pub struct Profile(f64);
impl Profile {
    pub fn constant(v: f64) -> Profile {
        Profile(v)
    }
    pub fn eval(&self, _x: f64, _b: f64) -> f64 {
        self.0
    }
}
