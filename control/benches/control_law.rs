//! One evaluation of the hybrid controller's law for the paper finger (criterion): the
//! computed-torque law of a free phase and the force/velocity law of a contact phase, at a
//! contact state of the paper scene. Run: `cargo bench -p bf-control --bench control_law --
//! --warm-up-time 1 --measurement-time 3`.

fn main() {}
