//! The paper's experiments (Sect. 6 and the appendices), built on the solve pipeline
//! ([`crate::pipeline`]) and written into `ball-finger paper`'s report and the `report`
//! command's comparisons.
//!
//! * [`scenarios`]: the three scenarios of Sect. 6.1 solved, verified, plotted and checked;
//! * [`claims`]: the paper's claims of Sect. 6.1 with verdicts and, where they differ, why;
//! * [`openloop`]: the optimal torques replayed open loop in the full hybrid model (Sect. 6.2);
//! * [`closed_loop`]: the same optima executed with feedback (bf-control; Sect. 6.2 and 7);
//! * [`replan`]: re-planning at each lift-off for the closed loop (the solve pipeline as
//!   bf-control's replanner);
//! * [`appendix`]: the paper's Appendix A/B as printed against derivations (the misprints);
//! * [`extremes`]: numerical stability at the edges of the domain (one file per probe);
//! * [`speed_accuracy`]: error versus computing time for integrators, collocation meshes, the
//!   smoothing ε and the generated-kernel variants (one file per study);
//! * [`report`]: the `report` command's studies (search strategies, the stick-phase minimum);
//! * [`stored`]: the global search's optima that the report presents, stored and re-solved.

pub mod appendix;
pub mod claims;
pub mod closed_loop;
pub mod extremes;
pub mod openloop;
pub mod replan;
pub mod report;
pub mod scenarios;
pub mod speed_accuracy;
pub mod stored;
