//! `hce bake --quality`: named points on the bake's error/time curve, each a set of the
//! solver's own flags (`--bf-epsilon`, `--detail-level`, `--visibility-rays`), measured on the
//! Cornell box against Blender Cycles by `tools/scripts/cycles-curve.sh` (BENCHMARKS.md,
//! "Against Blender Cycles"). A flag given explicitly overrides its preset's value.

use clap::ValueEnum;
use hce_bake::BakeParams;

/// A bake preset; each variant's help is the flags it stands for and where it lies on the
/// Cornell box's curve (BENCHMARKS.md, "The Cornell box against Blender Cycles": relative RMS
/// at the level-2 vertices against a many-seed Cycles reference, and time as a share of the
/// default's, which survives a faster solver better than seconds).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Quality {
    /// --bf-epsilon 1e-3 --detail-level 4 --visibility-rays 4 (Cornell box: 2.5% error, a
    /// twelfth of the default's time)
    Draft,
    /// --bf-epsilon 1e-4 --detail-level 7 --visibility-rays 8 (Cornell box: 1.2% error)
    Default,
    /// --bf-epsilon 1e-5 --detail-level 7 --visibility-rays 8 (Cornell box: 1.2% error, no
    /// better than the default there, in 3.5 times its time)
    High,
}

/// The solver parameters a preset sets; the rest are [`BakeParams::default`]'s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preset {
    pub bf_epsilon: f32,
    pub detail_level: u32,
    pub visibility_rays: u32,
}

impl Quality {
    pub fn preset(self) -> Preset {
        let default = BakeParams::default();
        match self {
            // Coarser links, shadows resolved to level 4 and half the rays: for previews and
            // iteration, twice the default's error in a twelfth of its time.
            Quality::Draft => Preset {
                bf_epsilon: 1e-3,
                detail_level: 4,
                visibility_rays: 4,
            },
            Quality::Default => Preset {
                bf_epsilon: default.bf_epsilon,
                detail_level: default.detail_level,
                visibility_rays: default.visibility_rays,
            },
            // Ten times finer links: the least error the solver reaches in minutes. On the
            // Cornell box it buys nothing (the error left there is discretisation, not links).
            Quality::High => Preset {
                bf_epsilon: 1e-5,
                ..Quality::Default.preset()
            },
        }
    }

    /// The preset's parameters with any explicitly given flag in place of its value.
    pub fn params(
        self,
        bf_epsilon: Option<f32>,
        detail_level: Option<u32>,
        visibility_rays: Option<u32>,
    ) -> BakeParams {
        let p = self.preset();
        BakeParams {
            bf_epsilon: bf_epsilon.unwrap_or(p.bf_epsilon),
            detail_level: detail_level.unwrap_or(p.detail_level),
            visibility_rays: visibility_rays.unwrap_or(p.visibility_rays),
            ..BakeParams::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_preset_is_the_solvers_default() {
        assert_eq!(
            Quality::Default.params(None, None, None),
            BakeParams::default()
        );
    }

    #[test]
    fn presets_parse_by_name() {
        for (name, q) in [
            ("draft", Quality::Draft),
            ("default", Quality::Default),
            ("high", Quality::High),
        ] {
            assert_eq!(Quality::from_str(name, false), Ok(q));
        }
        assert!(Quality::from_str("best", false).is_err());
    }

    #[test]
    fn explicit_flags_override_the_preset() {
        let p = Quality::Draft.params(Some(3e-5), None, Some(16));
        assert_eq!(p.bf_epsilon, 3e-5);
        assert_eq!(p.detail_level, 4);
        assert_eq!(p.visibility_rays, 16);
        let q = Quality::High.params(None, Some(6), None);
        assert_eq!(
            (q.bf_epsilon, q.detail_level, q.visibility_rays),
            (1e-5, 6, 8)
        );
    }

    #[test]
    fn every_preset_is_a_valid_parameter_set() {
        for q in Quality::value_variants() {
            q.params(None, None, None).validate().unwrap();
        }
    }
}
