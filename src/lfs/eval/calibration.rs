//! How good a failure probability is against what happened: ROC AUC (does it rank failures above passes?) and
//! the Brier score (is it calibrated?).

/// ROC AUC of `scores` for the `positive` outcomes: the probability that a random positive scores above a random
/// negative, ties counted half (the Mann-Whitney statistic). `None` without both classes or with a length
/// mismatch.
pub fn roc_auc(scores: &[f64], positive: &[bool]) -> Option<f64> {
    if scores.len() != positive.len() {
        return None;
    }
    let pos: Vec<f64> = scores
        .iter()
        .zip(positive)
        .filter(|(_, p)| **p)
        .map(|(s, _)| *s)
        .collect();
    let neg: Vec<f64> = scores
        .iter()
        .zip(positive)
        .filter(|(_, p)| !**p)
        .map(|(s, _)| *s)
        .collect();
    if pos.is_empty() || neg.is_empty() {
        return None;
    }
    let mut wins = 0.0;
    for p in &pos {
        for n in &neg {
            wins += if p > n {
                1.0
            } else if p == n {
                0.5
            } else {
                0.0
            };
        }
    }
    Some(wins / (pos.len() * neg.len()) as f64)
}

/// Mean squared difference between the probabilities and the 0/1 outcomes; `None` if empty or mismatched.
pub fn brier(probabilities: &[f64], outcome: &[bool]) -> Option<f64> {
    if probabilities.len() != outcome.len() || probabilities.is_empty() {
        return None;
    }
    let sum: f64 = probabilities
        .iter()
        .zip(outcome)
        .map(|(p, o)| (p - if *o { 1.0 } else { 0.0 }).powi(2))
        .sum();
    Some(sum / probabilities.len() as f64)
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn auc_by_hand() {
        // Positives 0.9, 0.4; negatives 0.5, 0.1: pairs (0.9>0.5, 0.9>0.1, 0.4<0.5, 0.4>0.1) = 3 of 4.
        let auc = roc_auc(&[0.9, 0.5, 0.4, 0.1], &[true, false, true, false]);
        assert_eq!(auc, Some(0.75));
        // A tie counts half: positive 0.5 vs negatives 0.5 and 0.2 -> (0.5 + 1) / 2.
        assert_eq!(roc_auc(&[0.5, 0.5, 0.2], &[true, false, false]), Some(0.75));
        assert_eq!(roc_auc(&[0.3, 0.3], &[true, false]), Some(0.5));
        assert_eq!(roc_auc(&[0.1, 0.9], &[true, false]), Some(0.0));
        assert_eq!(roc_auc(&[0.1, 0.9], &[true, true]), None);
        assert_eq!(roc_auc(&[0.1], &[true, false]), None);
    }

    #[test]
    fn brier_by_hand() {
        // (0.8 - 1)^2 = 0.04, (0.3 - 0)^2 = 0.09, (0.5 - 1)^2 = 0.25: mean 0.38 / 3.
        let b = brier(&[0.8, 0.3, 0.5], &[true, false, true]).unwrap();
        assert!((b - 0.38 / 3.0).abs() < 1e-15, "{b}");
        assert_eq!(brier(&[1.0, 0.0], &[true, false]), Some(0.0));
        assert_eq!(brier(&[1.0, 0.0], &[false, true]), Some(1.0));
        assert_eq!(brier(&[], &[]), None);
    }

    proptest! {
        #[test]
        fn auc_flips_with_the_labels(v in proptest::collection::vec((0.0..1.0f64, any::<bool>()), 2..30)) {
            let (s, l): (Vec<f64>, Vec<bool>) = v.into_iter().unzip();
            let flipped: Vec<bool> = l.iter().map(|x| !x).collect();
            if let (Some(a), Some(b)) = (roc_auc(&s, &l), roc_auc(&s, &flipped)) {
                prop_assert!((a + b - 1.0).abs() < 1e-12);
                prop_assert!((0.0..=1.0).contains(&a));
            }
        }
    }
}
