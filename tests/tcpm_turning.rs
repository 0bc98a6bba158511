//! TCPM on the table-table machine while the table turns: the tool tip stays on its
//! workpiece point, and the linear machine axes that carry it around the table axes stay
//! within their limits however far the tip is from those axes.

mod common;

use common::mill5::tip_of;
use common::{run, temp_program};
use klar::config::MachineConfig;

#[test]
fn rapid_table_turns_far_from_the_table_axis_keep_every_axis_within_its_limits() {
    // With the tip 300 mm from the C axis, C at its own 180 °/s would swing X and Y at
    // 942 mm/s; the machine allows 166 (Z 100).
    let text = "0 BEGIN PGM FAR MM\n\
                1 TOOL CALL 1 Z S3000\n\
                2 L Z+50 R0 FMAX M3\n\
                3 L X+300 Y+0 FMAX\n\
                4 L Z+5 FMAX M128\n\
                5 L C+90 FMAX\n\
                6 L A+20 C+180 FMAX\n\
                7 L A+0 C+0 FMAX\n\
                8 L Z+50 FMAX M129\n\
                9 END PGM FAR MM\n";
    let path = temp_program("far.h", text);
    let machine = MachineConfig::builtin_mill5();
    let (result, trace) = run(&path, &machine);
    result.unwrap_or_else(|f| panic!("{}", f.error));
    common::assert_within_limits(&trace, &machine);
    let cols: Vec<Vec<f64>> = ["X", "Y", "Z", "A", "C"]
        .iter()
        .map(|l| trace.column(l).expect("axis column"))
        .collect();
    let mut turning = 0;
    let [x, y, z, a, c] = [0, 1, 2, 3, 4].map(|k| &cols[k]);
    for i in 0..x.len() {
        let (a, c) = (a[i], c[i]);
        if a.abs() < 1e-9 && c.abs() < 1e-9 {
            continue;
        }
        turning += 1;
        let tip = tip_of([x[i], y[i], z[i]], a, c);
        for (k, want) in [300.0, 0.0, 5.0].iter().enumerate() {
            assert!((tip[k] - want).abs() < 1e-6, "row {i}: tip {tip:?}");
        }
    }
    assert!(turning > 100, "{turning} rows with the table turned");
}
