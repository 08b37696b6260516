//! Linear cells (ours, `cell_gradient`, docs/algorithm.md): a cell's AO read along its least-squares slope at
//! the pixel, instead of the cell's mean.
mod common;
use common::*;

/// One frame from an empty map at 8 rays per pixel on the cycloidal gearbox at 320x180 against its Cycles
/// reference, with constant cells and with linear cells over the same rays: the line reads the AO's slope across
/// a cell (contact shadows fading along a wall), so the error falls (measured 0.0189 -> 0.0177). The margin is
/// six times the run-to-run spread of one frame (thread order decides which pixel takes which of a cell's
/// rays). Contact detail is off: it brings back the same detail finer than a cell from the G-buffer.
#[test]
fn linear_cells_lower_the_first_frame_error() {
    let e = first_frame_errors(
        "cycloidal",
        320,
        180,
        &[
            r#"{"linear_cells": false, "contact_detail": false}"#,
            r#"{"linear_cells": true, "contact_detail": false}"#,
        ],
    );
    println!(
        "cycloidal 320x180, HRTAO 1 frame: constant cells {:.4}, linear cells {:.4}",
        e[0], e[1]
    );
    assert!(
        e[1] < e[0] - 0.0006,
        "cycloidal: constant {}, linear {}",
        e[0],
        e[1]
    );
}
