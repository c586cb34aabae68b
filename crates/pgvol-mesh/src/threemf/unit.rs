//! The length units a 3MF model may declare (core specification, `unit` of `<model>`).

use std::fmt;

/// The length unit a 3MF model declares; the reader converts coordinates to millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LengthUnit {
    Micron,
    Millimetre,
    Centimetre,
    Inch,
    Foot,
    Metre,
}

impl LengthUnit {
    const ALL: [LengthUnit; 6] = [
        LengthUnit::Micron,
        LengthUnit::Millimetre,
        LengthUnit::Centimetre,
        LengthUnit::Inch,
        LengthUnit::Foot,
        LengthUnit::Metre,
    ];

    /// The unit named by a `unit` attribute (3MF's spelling, as in `millimeter`).
    pub fn from_3mf(name: &str) -> Option<LengthUnit> {
        Self::ALL.into_iter().find(|u| u.name_3mf() == name)
    }

    /// The attribute value that names this unit in a 3MF file.
    pub fn name_3mf(self) -> &'static str {
        match self {
            LengthUnit::Micron => "micron",
            LengthUnit::Millimetre => "millimeter",
            LengthUnit::Centimetre => "centimeter",
            LengthUnit::Inch => "inch",
            LengthUnit::Foot => "foot",
            LengthUnit::Metre => "meter",
        }
    }

    /// Millimetres in one of this unit (exact: the inch is 25.4 mm by definition).
    pub fn millimetres(self) -> f64 {
        match self {
            LengthUnit::Micron => 0.001,
            LengthUnit::Millimetre => 1.0,
            LengthUnit::Centimetre => 10.0,
            LengthUnit::Inch => 25.4,
            LengthUnit::Foot => 304.8,
            LengthUnit::Metre => 1000.0,
        }
    }

    pub(super) fn expected() -> String {
        Self::ALL.map(LengthUnit::name_3mf).join(", ")
    }
}

/// The unit's English name (`inch`, `millimetre`).
impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LengthUnit::Micron => "micron",
            LengthUnit::Millimetre => "millimetre",
            LengthUnit::Centimetre => "centimetre",
            LengthUnit::Inch => "inch",
            LengthUnit::Foot => "foot",
            LengthUnit::Metre => "metre",
        })
    }
}

/// What a reader does with a length unit the file declares (3MF).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UnitChoice {
    /// Coordinates are converted to millimetres, so files in any unit come out alike.
    #[default]
    Millimetres,
    /// Coordinates are kept as the file writes them, in its declared unit.
    AsDeclared,
}

/// The length unit a file declared and what reading did with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DeclaredUnit {
    pub unit: LengthUnit,
    /// Whether the coordinates were converted to millimetres.
    pub converted: bool,
}

impl DeclaredUnit {
    /// The factor the file's coordinates were multiplied by.
    pub fn scale(self) -> f64 {
        if self.converted {
            self.unit.millimetres()
        } else {
            1.0
        }
    }
}

/// For reports: `inch -> millimetre x25.4`, `millimetre (as in the file)`, or `inch (as in the
/// file, not converted)`.
impl fmt::Display for DeclaredUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.unit, self.converted) {
            (LengthUnit::Millimetre, _) => f.write_str("millimetre (as in the file)"),
            (unit, true) => write!(f, "{unit} -> millimetre x{}", unit.millimetres()),
            (unit, false) => write!(f, "{unit} (as in the file, not converted)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_unit_reads_back_from_its_name_and_says_its_factor() {
        for u in LengthUnit::ALL {
            assert_eq!(LengthUnit::from_3mf(u.name_3mf()), Some(u));
        }
        assert_eq!(LengthUnit::from_3mf("Inch"), None);
        let read = |unit, converted| DeclaredUnit { unit, converted }.to_string();
        assert_eq!(read(LengthUnit::Inch, true), "inch -> millimetre x25.4");
        assert_eq!(
            read(LengthUnit::Micron, true),
            "micron -> millimetre x0.001"
        );
        assert_eq!(
            read(LengthUnit::Inch, false),
            "inch (as in the file, not converted)"
        );
        assert_eq!(
            read(LengthUnit::Millimetre, true),
            "millimetre (as in the file)"
        );
        assert!((LengthUnit::Foot.millimetres() - 12.0 * 25.4).abs() < 1e-12);
    }
}
