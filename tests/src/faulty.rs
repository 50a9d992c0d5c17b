//! Faults of a HIL file, for the images that read named channels from one (the rotor's and the
//! crank's): lines missing, a line replaced by garbage, an empty cell, a NaN and a junk line,
//! and the counts a node must report for them. One plan per image (`rotor::FAULTS`,
//! `crank::FAULTS`), one way to apply it.

use std::ops::Range;

/// Where the faults go, as sample numbers (data lines counted from 0 after the header).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultPlan {
    /// Lines deleted from the file: missing, bridged (stepped as missing) by their `t`.
    pub deleted: Range<usize>,
    /// A line replaced by garbage without a `t`: not stepped itself, bridged when the next
    /// line's `t` shows it missing.
    pub garbage: usize,
    /// A line whose first channel is emptied: stepped as missing, at its time.
    pub empty_cell: usize,
    /// A junk line is inserted after this one: not stepped.
    pub junk_after: usize,
    /// A line whose first channel reads NaN: stepped as missing.
    pub nan: usize,
}

impl FaultPlan {
    /// Lines that do not parse: the garbage, the empty cell, the junk, the NaN.
    pub const BAD_LINES: u32 = 4;
    /// Of those, lines without a `t`: the garbage and the junk.
    pub const UNTIMED_LINES: u32 = 2;

    /// Samples bridged for lines missing from the file: the deleted ones and the garbage one.
    ///
    /// ```
    /// let plan = edgekf_tests::faulty::FaultPlan { deleted: 10..30, garbage: 40, empty_cell: 50, junk_after: 60, nan: 70 };
    /// assert_eq!(plan.missing_lines(), 21);
    /// ```
    pub fn missing_lines(&self) -> u32 {
        self.deleted.len() as u32 + 1
    }

    /// Whether sample `k`'s line is gone from the faulty file (deleted or garbage).
    pub fn lost(&self, k: usize) -> bool {
        self.deleted.contains(&k) || k == self.garbage
    }

    /// Whether sample `k` reaches the node unusable (lost, emptied or NaN).
    pub fn unusable(&self, k: usize) -> bool {
        self.lost(k) || k == self.empty_cell || k == self.nan
    }

    /// `csv` (a header, then one line per sample, `t` first) with the plan's faults.
    ///
    /// ```
    /// let plan = edgekf_tests::faulty::FaultPlan { deleted: 1..2, garbage: 2, empty_cell: 3, junk_after: 4, nan: 5 };
    /// let csv = "t,a,b\n0,1,2\n1,1,2\n2,1,2\n3,1,2\n4,1,2\n5,1,2\n";
    /// assert_eq!(plan.apply(csv), "t,a,b\n0,1,2\n\u{1}%garbage%\n3,,2\n4,1,2\njunk,abc,,\n5,NaN,2\n");
    /// ```
    pub fn apply(&self, csv: &str) -> String {
        let mut out = String::new();
        for (k, line) in csv.lines().enumerate() {
            let Some(sample) = k.checked_sub(1) else {
                out.push_str(line);
                out.push('\n');
                continue;
            };
            if self.deleted.contains(&sample) {
                continue;
            }
            let mut fields: Vec<&str> = line.split(',').collect();
            if sample == self.garbage {
                fields = vec!["\u{1}%garbage%"];
            } else if let Some(first) = fields.get_mut(1) {
                if sample == self.empty_cell {
                    *first = "";
                } else if sample == self.nan {
                    *first = "NaN";
                }
            }
            out.push_str(&fields.join(","));
            out.push('\n');
            if sample == self.junk_after {
                out.push_str("junk,abc,,\n");
            }
        }
        out
    }
}
