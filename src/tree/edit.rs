//! Editing a written-out tree: changes to one support's numbers, a new child branch, deleting a
//! support with everything that forks from it. Every edit is checked by building the tree; an
//! edit that would break it is refused with the reason and changes nothing.

use super::{SupportDef, TreeDef};
use crate::foundation::values::{Degrees, Length, MAX_DEGREES, Radius, UnitInterval};

/// A number of a fork that the editor changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForkField {
    /// Where along the parent, 0 to 1.
    At,
    /// Initial heading, degrees.
    YawDeg,
    /// Initial pitch, degrees.
    PitchDeg,
    /// Length, metres.
    Length,
    /// Radius at the start, metres.
    RadiusStart,
    /// Radius at the tip, metres.
    RadiusEnd,
    /// Change of heading to the tip, degrees.
    BendYawDeg,
    /// Change of pitch to the tip, degrees.
    BendPitchDeg,
}

impl ForkField {
    /// Every field, in panel order, with its label and slider range.
    pub const ALL: [(ForkField, &'static str, f32, f32); 8] = [
        (ForkField::At, "at", 0.0, 1.0),
        (ForkField::YawDeg, "yaw_deg", -180.0, 180.0),
        (ForkField::PitchDeg, "pitch_deg", -90.0, 90.0),
        (ForkField::Length, "length", 0.05, 20.0),
        (ForkField::RadiusStart, "radius start", 0.005, 1.0),
        (ForkField::RadiusEnd, "radius tip", 0.005, 1.0),
        (ForkField::BendYawDeg, "bend yaw_deg", -180.0, 180.0),
        (ForkField::BendPitchDeg, "bend pitch_deg", -90.0, 90.0),
    ];
}

/// One change to a tree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Edit {
    /// Set a number of fork `support`.
    Fork {
        /// The support's index.
        support: usize,
        /// Which number.
        field: ForkField,
        /// Its new value.
        value: f32,
    },
    /// Set the radius of polyline `support` at point `point`, metres.
    Radius {
        /// The support's index.
        support: usize,
        /// The point's index.
        point: usize,
        /// The new radius.
        value: f32,
    },
    /// Add a branch forking from the middle of `parent`.
    AddChild {
        /// The parent support's index.
        parent: usize,
    },
    /// Delete `support` and every support forking from it, directly or not.
    Delete {
        /// The support's index.
        support: usize,
    },
}

/// The value a fork field currently has.
pub fn fork_value(support: &SupportDef, field: ForkField) -> Option<f32> {
    let radius = support.radius.map(|r| r.map(|r| r.0));
    let bend = support.bend_deg.map_or([0.0; 2], |b| b.map(|d| d.0));
    support.parent.as_ref()?;
    Some(match field {
        ForkField::At => support.at?.0,
        ForkField::YawDeg => support.yaw_deg.map_or(0.0, |d| d.0),
        ForkField::PitchDeg => support.pitch_deg.map_or(0.0, |d| d.0),
        ForkField::Length => support.length?.0,
        ForkField::RadiusStart => radius?[0],
        ForkField::RadiusEnd => radius?[1],
        ForkField::BendYawDeg => bend[0],
        ForkField::BendPitchDeg => bend[1],
    })
}

/// `def` with `edit` applied, or why not. Generated trees cannot be edited (their supports are
/// not written out).
pub fn apply(def: &TreeDef, edit: Edit) -> Result<TreeDef, String> {
    if def.generate.is_some() {
        return Err("a generated tree has no written supports to edit; `canopy tree generate` writes them out".into());
    }
    let mut new = def.clone();
    let count = new.supports.len();
    let support = |index: usize| if index < count { Ok(index) } else { Err(format!("no support {index}")) };
    let finite = |value: f32| if value.is_finite() { Ok(value) } else { Err(format!("{value} is not a number")) };
    match edit {
        Edit::Fork { support: index, field, value } => {
            let value = finite(value)?;
            let target = &mut new.supports[support(index)?];
            if target.parent.is_none() {
                return Err(format!("\"{}\" is a polyline, not a fork", target.name));
            }
            let positive = |max: f32| {
                if value > 0.0 && value <= max {
                    Ok(value)
                } else {
                    Err(format!("expected more than 0 and at most {max}"))
                }
            };
            let angle = |value: f32| {
                if f64::from(value.abs()) <= MAX_DEGREES {
                    Ok(Degrees(value))
                } else {
                    Err("expected at most 36000 degrees".to_string())
                }
            };
            match field {
                ForkField::At if (0.0..=1.0).contains(&value) => target.at = Some(UnitInterval(value)),
                ForkField::At => return Err("at: expected 0 to 1".into()),
                ForkField::YawDeg => target.yaw_deg = Some(angle(value)?),
                ForkField::PitchDeg => target.pitch_deg = Some(angle(value)?),
                ForkField::Length => target.length = Some(Length(positive(1000.0)?)),
                ForkField::RadiusStart => target.radius.get_or_insert([Radius(0.05); 2])[0] = Radius(positive(100.0)?),
                ForkField::RadiusEnd => target.radius.get_or_insert([Radius(0.05); 2])[1] = Radius(positive(100.0)?),
                ForkField::BendYawDeg => target.bend_deg.get_or_insert([Degrees(0.0); 2])[0] = angle(value)?,
                ForkField::BendPitchDeg => target.bend_deg.get_or_insert([Degrees(0.0); 2])[1] = angle(value)?,
            }
        }
        Edit::Radius { support: index, point, value } => {
            let value = finite(value)?;
            if !(value > 0.0 && value <= 100.0) {
                return Err("radius: expected more than 0 and at most 100 m".into());
            }
            let target = &mut new.supports[support(index)?];
            let radius = target.radii.as_mut().and_then(|r| r.get_mut(point)).ok_or("no such point")?;
            *radius = Radius(value);
        }
        Edit::AddChild { parent } => {
            let parent_name = new.supports[support(parent)?].name.clone();
            let name = (1..)
                .map(|n| format!("{parent_name}-{n}"))
                .find(|name| new.supports.iter().all(|s| &s.name != name))
                .expect("an unbounded range always yields a free name");
            let start = def.build().ok().map_or(0.05, |tree| tree.supports[parent].at(0.5).2 * 0.6).max(0.005);
            new.supports.push(SupportDef {
                name,
                kind: None,
                points: None,
                radii: None,
                parent: Some(parent_name),
                at: Some(UnitInterval(0.5)),
                yaw_deg: Some(Degrees(90.0)),
                pitch_deg: Some(Degrees(20.0)),
                length: Some(Length(1.0)),
                radius: Some([Radius(start), Radius((start * 0.4).max(0.003))]),
                bend_deg: None,
                sections: None,
            });
        }
        Edit::Delete { support: index } => {
            let mut doomed = vec![new.supports[support(index)?].name.clone()];
            // Forks of doomed supports are doomed too, until nothing more is added.
            while let Some(next) = new
                .supports
                .iter()
                .find(|s| !doomed.contains(&s.name) && s.parent.as_ref().is_some_and(|p| doomed.contains(p)))
            {
                doomed.push(next.name.clone());
            }
            new.supports.retain(|s| !doomed.contains(&s.name));
            if new.supports.is_empty() {
                return Err("a tree keeps at least one support".into());
            }
        }
    }
    new.build().map_err(|error| error.to_string())?;
    Ok(new)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn oak() -> TreeDef {
        serde_yaml::from_str(
            "supports:
               - { name: trunk, points: [[0, 0, 0], [0, 4, 0]], radii: [0.3, 0.2] }
               - { name: low, parent: trunk, at: 0.3, yaw_deg: 90, length: 2, radius: [0.1, 0.05] }
               - { name: twig, parent: low, at: 0.5, length: 0.5, radius: [0.03, 0.01] }
               - { name: high, parent: trunk, at: 0.8, length: 1, radius: [0.08, 0.03] }",
        )
        .unwrap()
    }

    #[test]
    fn fork_numbers_change_and_the_tree_follows() {
        let def = apply(&oak(), Edit::Fork { support: 1, field: ForkField::Length, value: 3.0 }).unwrap();
        assert_eq!(fork_value(&def.supports[1], ForkField::Length), Some(3.0));
        assert!((def.build().unwrap().supports[1].length() - 3.0).abs() < 1e-5);
        let def = apply(&def, Edit::Fork { support: 1, field: ForkField::BendPitchDeg, value: -30.0 }).unwrap();
        assert_eq!(fork_value(&def.supports[1], ForkField::BendPitchDeg), Some(-30.0));
        let def = apply(&def, Edit::Radius { support: 0, point: 1, value: 0.25 }).unwrap();
        assert_eq!(def.build().unwrap().supports[0].radii, vec![0.3, 0.25]);
    }

    #[test]
    fn bad_edits_are_refused_and_change_nothing() {
        let def = oak();
        for edit in [
            Edit::Fork { support: 1, field: ForkField::At, value: 1.5 },
            Edit::Fork { support: 1, field: ForkField::Length, value: 0.0 },
            Edit::Fork { support: 1, field: ForkField::YawDeg, value: f32::NAN },
            Edit::Fork { support: 0, field: ForkField::Length, value: 1.0 },
            Edit::Radius { support: 0, point: 5, value: 0.1 },
            Edit::Delete { support: 9 },
        ] {
            assert!(apply(&def, edit).is_err(), "{edit:?}");
        }
        assert_eq!(def, oak());
    }

    #[test]
    fn children_are_added_with_free_names_and_deleting_takes_their_forks() {
        let def = apply(&oak(), Edit::AddChild { parent: 1 }).unwrap();
        let def = apply(&def, Edit::AddChild { parent: 1 }).unwrap();
        let names: Vec<&str> = def.supports.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["trunk", "low", "twig", "high", "low-1", "low-2"]);
        let def = apply(&def, Edit::Delete { support: 1 }).unwrap();
        let names: Vec<&str> = def.supports.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["trunk", "high"]);
        assert!(apply(&apply(&def, Edit::Delete { support: 1 }).unwrap(), Edit::Delete { support: 0 }).is_err());
    }
}
