//! The 60 fault records at 12 kHz with the fault at the drive end of the Case Western Reserve
//! University Bearing Data Center, as public metadata: what was damaged, how much, at which
//! load, and how Smith & Randall's benchmark grades them. The runner takes the expected
//! answer from here, never from the data.
//!
//! Record numbers, faults, sizes, loads and outer-race positions are the Bearing Data Center's
//! listing (<https://engineering.case.edu/bearingdatacenter/12k-drive-end-bearing-fault-data>);
//! the file names of the GitHub mirror (`12k_Drive_End_<fault>_<load>_<record>.mat`) say the
//! same. Nominal speeds per load are the Center's (0 hp 1797, 1 hp 1772, 2 hp 1750, 3 hp 1730
//! rpm).

/// What was damaged (electro-discharge machining, at the drive-end bearing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Fault {
    /// The inner race: its defect line is BPFI.
    InnerRace,
    /// A rolling element: BSF (its cage modulation and 2×BSF are the same family).
    Ball,
    /// The outer race: BPFO.
    OuterRace,
}

impl Fault {
    /// The three, in the table's order.
    pub const ALL: [Fault; 3] = [Fault::InnerRace, Fault::Ball, Fault::OuterRace];

    /// The code of the mirror's file names (`IR`, `B`, `OR`).
    pub fn code(self) -> &'static str {
        match self {
            Fault::InnerRace => "IR",
            Fault::Ball => "B",
            Fault::OuterRace => "OR",
        }
    }

    /// The defect family the loop should name (`line` of its `bearing_defect`).
    pub fn family(self) -> &'static str {
        match self {
            Fault::InnerRace => "BPFI",
            Fault::Ball => "BSF",
            Fault::OuterRace => "BPFO",
        }
    }

    /// In words, for the table.
    pub fn name(self) -> &'static str {
        match self {
            Fault::InnerRace => "inner race",
            Fault::Ball => "ball",
            Fault::OuterRace => "outer race",
        }
    }
}

/// Smith & Randall's grade of a record (W. A. Smith, R. B. Randall, "Rolling element bearing
/// diagnostics using the Case Western Reserve University data: A benchmark study", MSSP 64–65
/// (2015) 100–131): Y diagnosable (Y1 with the fault's classic signature, Y2 with some
/// non-classic features), P partially diagnosable (P1 probably, P2 potentially), N not
/// diagnosable (N1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Grade {
    /// Clearly diagnosable, classic characteristics.
    Y1,
    /// Clearly diagnosable, some non-classic characteristics.
    Y2,
    /// Partially diagnosable: probably.
    P1,
    /// Partially diagnosable: potentially.
    P2,
    /// Not diagnosable.
    N1,
}

impl Grade {
    /// Whether the benchmark diagnoses the record (Y1 or Y2): 44 of the 60.
    pub fn diagnosable(self) -> bool {
        matches!(self, Grade::Y1 | Grade::Y2)
    }

    /// As the benchmark writes it.
    pub fn label(self) -> &'static str {
        match self {
            Grade::Y1 => "Y1",
            Grade::Y2 => "Y2",
            Grade::P1 => "P1",
            Grade::P2 => "P2",
            Grade::N1 => "N1",
        }
    }
}

/// One record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Record {
    /// The Center's number (105, …, 3008).
    pub number: u32,
    /// What was damaged.
    pub fault: Fault,
    /// The defect's diameter, thousandths of an inch (7, 14, 21, 28).
    pub size: u32,
    /// Motor load, hp (0–3).
    pub load_hp: u8,
    /// Outer race only: where the damage sits, o'clock (6 in the load zone, 3 orthogonal, 12
    /// opposite).
    pub position: Option<u8>,
    /// Smith & Randall's grade.
    pub grade: Grade,
}

impl Record {
    /// The mirror's fault label: `IR007`, `B014`, `OR021@3`.
    pub fn label(&self) -> String {
        let base = format!("{}{:03}", self.fault.code(), self.size);
        match self.position {
            Some(p) => format!("{base}@{p}"),
            None => base,
        }
    }

    /// The mirror's file stem: `12k_Drive_End_OR007@3_0_144`.
    pub fn mirror_stem(&self) -> String {
        format!("12k_Drive_End_{}_{}_{}", self.label(), self.load_hp, self.number)
    }

    /// The Center's nominal speed at the record's load, rpm.
    pub fn nominal_rpm(&self) -> u32 {
        [1797, 1772, 1750, 1730][usize::from(self.load_hp.min(3))]
    }

    /// Whether the record holds only the drive-end channel: the 0.028 in records (3001–3008)
    /// come from another test series, without the fan end and without the RPM.
    pub fn drive_end_only(&self) -> bool {
        self.size == 28
    }

    /// What the table says is expected: `outer race 0.007 in @3, 0 hp (BPFO)`.
    pub fn expected(&self) -> String {
        let at = self.position.map(|p| format!(" @{p}")).unwrap_or_default();
        format!("{} 0.{:03} in{at}, {} hp ({})", self.fault.name(), self.size, self.load_hp, self.fault.family())
    }
}

/// Four records of one fault, size and position at 0, 1, 2 and 3 hp, with their grades.
struct Group {
    fault: Fault,
    size: u32,
    position: Option<u8>,
    numbers: [u32; 4],
    grades: [Grade; 4],
}

use Fault::{Ball, InnerRace, OuterRace};
use Grade::{N1, P1, P2, Y1, Y2};

/// The 15 groups. The grades are Smith & Randall's as restated record by record (strata
/// `Y1`…`N1`) in the open CWRU benchmark of predictive-maintenance-mcp:
/// <https://github.com/LGDiMaggio/predictive-maintenance-mcp/blob/ba6c33bf2fe865562c349ab0fc01aa035d1c1040/benchmarks/cwru/results/results.json>
/// (`records.<id>.stratum`), its ids mapped to record numbers by
/// <https://github.com/LGDiMaggio/predictive-maintenance-mcp/blob/a596b8ef759dec546b35e7775d9b87477d79fb9e/benchmarks/cwru/records_ops.json>
/// (`opaque_id` → `file_id`). They give the totals issue #35 quotes from the paper: 44 of 60
/// diagnosable, inner race 12/16, ball 7/16, outer race 25/28 (a test checks these).
const GROUPS: [Group; 15] = [
    Group { fault: InnerRace, size: 7, position: None, numbers: [105, 106, 107, 108], grades: [Y2, Y2, Y2, Y2] },
    Group { fault: InnerRace, size: 14, position: None, numbers: [169, 170, 171, 172], grades: [Y2, Y2, Y2, Y2] },
    Group { fault: InnerRace, size: 21, position: None, numbers: [209, 210, 211, 212], grades: [Y1, Y1, Y1, Y1] },
    Group { fault: InnerRace, size: 28, position: None, numbers: [3001, 3002, 3003, 3004], grades: [N1, N1, N1, N1] },
    Group { fault: Ball, size: 7, position: None, numbers: [118, 119, 120, 121], grades: [N1, N1, N1, Y2] },
    Group { fault: Ball, size: 14, position: None, numbers: [185, 186, 187, 188], grades: [P2, P2, P2, P2] },
    Group { fault: Ball, size: 21, position: None, numbers: [222, 223, 224, 225], grades: [Y2, Y2, N1, N1] },
    Group { fault: Ball, size: 28, position: None, numbers: [3005, 3006, 3007, 3008], grades: [Y2, Y2, Y2, Y2] },
    Group { fault: OuterRace, size: 7, position: Some(6), numbers: [130, 131, 132, 133], grades: [Y1, Y1, Y1, Y1] },
    Group { fault: OuterRace, size: 7, position: Some(3), numbers: [144, 145, 146, 147], grades: [Y2, Y2, Y2, Y2] },
    Group { fault: OuterRace, size: 7, position: Some(12), numbers: [156, 158, 159, 160], grades: [Y1, Y2, Y2, Y2] },
    Group { fault: OuterRace, size: 14, position: Some(6), numbers: [197, 198, 199, 200], grades: [Y2, P2, P1, N1] },
    Group { fault: OuterRace, size: 21, position: Some(6), numbers: [234, 235, 236, 237], grades: [Y2, Y2, Y2, Y2] },
    Group { fault: OuterRace, size: 21, position: Some(3), numbers: [246, 247, 248, 249], grades: [Y2, Y2, Y2, Y2] },
    Group { fault: OuterRace, size: 21, position: Some(12), numbers: [258, 259, 260, 261], grades: [Y2, Y2, Y2, Y2] },
];

/// All 60 records, group by group, 0 hp first.
pub fn records() -> Vec<Record> {
    GROUPS
        .iter()
        .flat_map(|g| {
            (0..4).map(move |load| Record {
                number: g.numbers[load],
                fault: g.fault,
                size: g.size,
                load_hp: load as u8,
                position: g.position,
                grade: g.grades[load],
            })
        })
        .collect()
}

/// The record numbered `number`, if it is one of the 60.
pub fn find(number: u32) -> Option<Record> {
    records().into_iter().find(|r| r.number == number)
}

/// The record a file in the data folder holds, from its name: `<record>.csv` (`105.csv`,
/// `0105.csv`) or the mirror's `12k_Drive_End_<fault>_<load>_<record>.csv`. `Ok(None)` for
/// any other file (the healthy `097*.csv`, notes, …); an error for a mirror-style name whose
/// fault or load contradicts its record number (a mislabelled file would be scored against
/// the wrong answer).
pub fn from_file_name(name: &str) -> Result<Option<Record>, String> {
    let Some(stem) = name.strip_suffix(".csv") else { return Ok(None) };
    if !stem.is_empty() && stem.bytes().all(|b| b.is_ascii_digit()) {
        return Ok(stem.parse().ok().and_then(find));
    }
    let Some(rest) = stem.strip_prefix("12k_Drive_End_") else { return Ok(None) };
    let mut parts = rest.rsplitn(3, '_');
    let (Some(number), Some(load), Some(label)) = (parts.next(), parts.next(), parts.next()) else {
        return Ok(None);
    };
    let Some(record) = number.parse().ok().and_then(find) else { return Ok(None) };
    if stem != record.mirror_stem() {
        return Err(format!(
            "{name}: the name says {label} at {load} hp, but record {} is {} at {} hp",
            record.number,
            record.label(),
            record.load_hp
        ));
    }
    Ok(Some(record))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_catalogue_holds_sixty_distinct_records() {
        let all = records();
        assert_eq!(all.len(), 60);
        let mut numbers: Vec<u32> = all.iter().map(|r| r.number).collect();
        numbers.sort_unstable();
        numbers.dedup();
        assert_eq!(numbers.len(), 60);
        assert_eq!(all.iter().filter(|r| r.load_hp <= 1).count(), 30);
        assert_eq!(
            all.iter().filter(|r| r.drive_end_only()).map(|r| r.number).collect::<Vec<_>>(),
            (3001..=3008).collect::<Vec<_>>()
        );
    }

    #[test]
    fn the_grades_give_the_benchmarks_totals() {
        let all = records();
        let diagnosable = |f: Fault| all.iter().filter(|r| r.fault == f && r.grade.diagnosable()).count();
        let of = |f: Fault| all.iter().filter(|r| r.fault == f).count();
        assert_eq!((diagnosable(InnerRace), of(InnerRace)), (12, 16));
        assert_eq!((diagnosable(Ball), of(Ball)), (7, 16));
        assert_eq!((diagnosable(OuterRace), of(OuterRace)), (25, 28));
    }

    #[test]
    fn labels_and_names_are_the_mirrors() {
        let r = find(144).unwrap();
        assert_eq!((r.fault, r.size, r.load_hp, r.position), (OuterRace, 7, 0, Some(3)));
        assert_eq!(r.mirror_stem(), "12k_Drive_End_OR007@3_0_144");
        assert_eq!(r.expected(), "outer race 0.007 in @3, 0 hp (BPFO)");
        let b = find(3007).unwrap();
        assert_eq!((b.label(), b.load_hp, b.nominal_rpm()), ("B028".to_string(), 2, 1750));
        assert_eq!(find(158).unwrap().load_hp, 1);
        assert_eq!(find(157), None);
    }

    #[test]
    fn file_names_are_recognised_both_ways() {
        assert_eq!(from_file_name("105.csv").unwrap().map(|r| r.number), Some(105));
        assert_eq!(from_file_name("3005.csv").unwrap().map(|r| r.fault), Some(Ball));
        let mirror = from_file_name("12k_Drive_End_OR021@12_3_261.csv").unwrap().unwrap();
        assert_eq!((mirror.number, mirror.position, mirror.load_hp), (261, Some(12), 3));
        for other in ["097.csv", "097a.csv", "105.mat", "notes.txt", ".csv", "12k_Drive_End_IR007_0.csv", "999.csv"] {
            assert_eq!(from_file_name(other), Ok(None), "{other}");
        }
        let wrong = from_file_name("12k_Drive_End_IR007_1_105.csv").unwrap_err();
        assert!(wrong.contains("record 105 is IR007 at 0 hp"), "{wrong}");
        assert!(from_file_name("12k_Drive_End_B007_0_105.csv").is_err());
    }
}
