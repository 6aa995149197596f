//! From what was asked to the settings a campaign runs with: every default filled in, the ones that depend on
//! the campaign's setup by [`super::rules`] (each named in its setting's declaration), and the settings that
//! constrain others applied (no screening, no learning; Collision Prevention draws gates). A program calling
//! the library gets the same campaign as the command line from the same request.

use super::keys::{CampaignAsked, VehiclesAsked};
use super::request::Request;
use super::rules::{Setup, profile_gusts};
use super::stored::CampaignSettings;
use crate::bridge::FlyMode;
use crate::generator::Family;

/// The setup `request` asks for.
pub fn setup_of(request: &Request) -> Setup {
    let a = &request.asked;
    let profile = a.mock.profile();
    Setup {
        budget: a.campaign.budget.unwrap_or(0),
        mode: a.campaign.mode(),
        mock: on_mock(&a.vehicles),
        profile,
        gusts_m_s2: a.mock.gust_acc_m_s2.unwrap_or_else(|| profile_gusts(profile)),
        jobs: a.vehicles.jobs,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        bench: a.vehicles.bench(),
    }
}

fn on_mock(v: &VehiclesAsked) -> bool {
    v.runner.is_none() && v.px4.is_none() && v.connect() == ["mock"]
}

impl CampaignSettings {
    /// The settings `request` asks for, every default filled in; an error names a required setting not given.
    pub fn resolve(request: &Request) -> Result<Self, String> {
        let setup = setup_of(request);
        let a = &request.asked;
        let mut s = Self {
            campaign: a.campaign.resolve(&setup)?,
            vehicles: a.vehicles.resolve(&setup)?,
            generator: request.generator(),
            output: a.output.resolve(&setup)?,
            screening: a.screening.resolve(&setup)?,
            mock: a.mock.resolve(&setup)?,
            flight: a.flight.resolve(&setup)?,
            learning: a.learning.resolve(&setup)?,
        };
        // Collision Prevention is tested with gates unless another family was asked for.
        if s.campaign.mode == FlyMode::CollisionPrevention && !request.gives("generator", "family") {
            s.generator.family = Family::Gate;
        }
        // Settings that turn others off, so every stage reads the effective value.
        s.learning.learn &= s.screening.screen;
        s.learning.adapt &= s.learning.learn;
        Ok(s)
    }
}

impl CampaignAsked {
    /// Whether a new campaign was asked for: CASE and BUDGET both given.
    pub fn is_new(&self) -> bool {
        self.case.is_some() && self.budget.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::settings::rules;
    use crate::campaign::settings::{Loaded, find};

    fn request(flags: &[(&str, &str, toml::Value)]) -> Request {
        let mut given = vec![
            (
                find("campaign", "case").unwrap(),
                toml::Value::String("missions/mission2.yaml".into()),
            ),
            (find("campaign", "budget").unwrap(), toml::Value::Integer(20)),
        ];
        given.extend(flags.iter().map(|(s, k, v)| (find(s, k).unwrap(), v.clone())));
        Request::new(&Loaded::default(), &given).unwrap()
    }

    #[test]
    fn the_setup_rules_fill_what_was_not_asked() {
        let s = CampaignSettings::resolve(&request(&[])).unwrap();
        assert_eq!(s.screening.candidates, 60);
        assert_eq!(s.screening.ensemble, 0);
        assert_eq!(s.mock.speed, rules::MOCK_SPEED);
        assert_eq!(s.flight.confirm, 3, "the default mock profile has PX4's scatter");
        assert!(!s.flight.overlap);
        let cp = request(&[("campaign", "mode", "collision-prevention".into())]);
        let s = CampaignSettings::resolve(&cp).unwrap();
        assert_eq!((s.mock.speed, s.generator.family), (rules::CP_MOCK_SPEED, Family::Gate));
        assert_eq!(s.flight.confirm, 1, "the mock's gusts fly only in avoidance mode");
        let link = request(&[(
            "vehicles",
            "connect",
            toml::Value::Array(vec!["udpin:0.0.0.0:14540".into()]),
        )]);
        let s = CampaignSettings::resolve(&link).unwrap();
        assert_eq!((s.screening.ensemble, s.flight.confirm, s.flight.overlap), (8, 3, true));
    }

    #[test]
    fn what_is_asked_wins_over_every_rule() {
        let r = request(&[
            ("campaign", "mode", "collision-prevention".into()),
            ("mock", "speed", toml::Value::Float(50.0)),
            ("generator", "family", "paper".into()),
            ("flight", "confirm", toml::Value::Integer(5)),
        ]);
        let s = CampaignSettings::resolve(&r).unwrap();
        assert_eq!(
            (s.mock.speed, s.generator.family, s.flight.confirm),
            (50.0, Family::Paper, 5)
        );
        let quiet = request(&[("mock", "profile", "competition".into())]);
        assert_eq!(
            CampaignSettings::resolve(&quiet).unwrap().flight.confirm,
            1,
            "its flights repeat"
        );
    }

    #[test]
    fn no_screening_turns_learning_off_and_a_missing_budget_is_named() {
        let r = request(&[("screening", "screen", toml::Value::Boolean(false))]);
        let s = CampaignSettings::resolve(&r).unwrap();
        assert!(!s.learning.learn && !s.learning.adapt && !s.learns());
        let none = Request::new(&Loaded::default(), &[]).unwrap();
        let e = CampaignSettings::resolve(&none).unwrap_err();
        assert!(e.contains("campaign.case"), "{e}");
    }
}
