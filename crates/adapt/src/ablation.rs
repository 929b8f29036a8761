//! The seed's ablation (its Table 1) for one character: which adapters `faceanim adapt
//! --ablation` trains side by side — features × calibration × augmentation at this crate's
//! network, then the seed's own architectures and loss, and the choices this crate made
//! against them (the censored loss, two networks).

use crate::adapter::{Activation, Architecture};
use crate::augment::Augmentation;
use crate::features::{Calibration, FeatureSet};
use crate::locality::Locality;
use crate::train::{Loss, TrainOptions};

/// One row of the table: the training set's augmentation and how the adapter is trained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    /// Which training set (its renders' augmentation).
    pub augmentation: Augmentation,
    /// The network, its loss and how many networks are averaged.
    pub options: TrainOptions,
}

/// The rows, each trained with `base`'s other settings (learning rate, epochs, seed).
#[must_use]
pub fn experiments(base: &TrainOptions) -> Vec<Experiment> {
    let default = Architecture::default();
    let row = |augmentation, architecture, loss, members| Experiment {
        augmentation,
        options: TrainOptions {
            architecture,
            loss,
            members,
            ..*base
        },
    };
    let mut rows = Vec::new();
    for augmentation in [Augmentation::None, Augmentation::Randomised] {
        for features in [FeatureSet::Scores, FeatureSet::Landmarks, FeatureSet::Both] {
            for calibration in [Calibration::None, Calibration::Neutral] {
                let architecture = Architecture {
                    features,
                    calibration,
                    ..default
                };
                rows.push(row(augmentation, architecture, base.loss, base.members));
            }
        }
    }
    let seed = Architecture::global();
    for architecture in [
        seed,
        Architecture {
            frame: default.frame,
            ..seed
        },
        Architecture {
            hidden: 100,
            ..seed
        },
        Architecture {
            hidden: 384,
            ..seed
        },
        Architecture {
            activation: Activation::Relu,
            clamp: false,
            ..default
        },
        Architecture {
            activation: Activation::Relu,
            ..default
        },
        Architecture {
            clamp: false,
            ..default
        },
    ] {
        // The censored loss knows the outputs end in [0, 1]: the seed's rows without the
        // clamp are trained as the seed trains them.
        let loss = if architecture.clamp {
            base.loss
        } else {
            Loss::SquaredClamped
        };
        // The seed trains one network over everything.
        let members = if architecture.locality == Locality::Global {
            1
        } else {
            base.members
        };
        rows.push(row(Augmentation::Randomised, architecture, loss, members));
    }
    if base.loss != Loss::SquaredClamped {
        rows.push(row(
            Augmentation::Randomised,
            default,
            Loss::SquaredClamped,
            base.members,
        ));
    }
    if base.members != 1 {
        rows.push(row(Augmentation::Randomised, default, base.loss, 1));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_holds_the_seeds_rows_and_ours_against_them() {
        let base = TrainOptions::default();
        let rows = experiments(&base);
        // 2 augmentations × 3 feature sets × 2 calibrations, 7 architectures, the seed's loss
        // and one network.
        assert_eq!(rows.len(), 12 + 7 + 2);
        assert!(rows.iter().all(|r| r.options.max_epochs == base.max_epochs));
        let seed = &rows[12];
        assert_eq!(seed.options.architecture, Architecture::global());
        assert_eq!(seed.options.members, 1, "the seed trains one network");
        // Every row without the clamp is trained with the seed's loss.
        assert!(
            rows.iter()
                .filter(|r| !r.options.architecture.clamp)
                .all(|r| r.options.loss == Loss::SquaredClamped)
        );
        // Trained with the seed's loss and one network already, the last two rows are not
        // repeated.
        let seeds = experiments(&TrainOptions {
            loss: Loss::SquaredClamped,
            members: 1,
            ..base
        });
        assert_eq!(seeds.len(), 12 + 7);
    }
}
