//! PX4's parameter table and the PARAM_* protocol, with values typed as PX4 sends them.
//!
//! PX4 advertises `MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE`: an INT32 parameter travels as
//! the bit pattern of the i32 inside the `f32` field, not as a converted float.

use mavlink::dialects::common::{
    MavMessage, MavParamType, MavSeverity, PARAM_REQUEST_READ_DATA, PARAM_SET_DATA, PARAM_VALUE_DATA,
};

/// A parameter value with the type PX4 declares for it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamValue {
    /// `MAV_PARAM_TYPE_INT32`.
    Int(i32),
    /// `MAV_PARAM_TYPE_REAL32`.
    Float(f32),
}

impl ParamValue {
    /// The value as f64 (ints converted numerically).
    pub fn as_f64(self) -> f64 {
        match self {
            ParamValue::Int(i) => f64::from(i),
            ParamValue::Float(f) => f64::from(f),
        }
    }

    /// The MAVLink wire encoding (bytewise for ints) and type.
    pub fn to_wire(self) -> (f32, MavParamType) {
        match self {
            ParamValue::Int(i) => (f32::from_bits(i as u32), MavParamType::MAV_PARAM_TYPE_INT32),
            ParamValue::Float(f) => (f, MavParamType::MAV_PARAM_TYPE_REAL32),
        }
    }
}

/// PX4 (v1.14) defaults for the parameters the mock uses, plus the case-study parameters.
const DEFAULTS: &[(&str, ParamValue)] = {
    use ParamValue::{Float as F, Int as I};
    &[
        ("COM_DISARM_LAND", F(2.0)),
        ("COM_DISARM_PRFLT", F(10.0)),
        ("COM_OBS_AVOID", I(0)),
        ("COM_OBL_RC_ACT", I(0)),
        ("COM_FAIL_ACT_T", F(5.0)),
        ("COM_OF_LOSS_T", F(0.5)),
        ("COM_RCL_EXCEPT", I(0)),
        ("COM_RC_LOSS_T", F(0.5)),
        // Collision Prevention (collisionprevention_params.c): off until CP_DIST > 0.
        ("CP_DELAY", F(0.4)),
        ("CP_DIST", F(-1.0)),
        ("CP_GO_NO_DATA", I(0)),
        ("CP_GUIDE_ANG", F(30.0)),
        ("GF_ACTION", I(2)),
        // src/modules/navigator/mission_params.c line 89.
        ("MIS_DIST_1WP", F(900.0)),
        // Land detector (land_detector_params_mc.c).
        ("LNDMC_TRIG_TIME", F(1.0)),
        ("LNDMC_XY_VEL_MAX", F(1.5)),
        ("LNDMC_Z_VEL_MAX", F(0.25)),
        ("MIS_TAKEOFF_ALT", F(2.5)),
        ("MIS_YAW_ERR", F(12.0)),
        ("MPC_ACC_DOWN_MAX", F(3.0)),
        ("MPC_ACC_HOR", F(3.0)),
        ("MPC_ACC_HOR_MAX", F(5.0)),
        ("MPC_ACC_UP_MAX", F(4.0)),
        ("MPC_HOLD_DZ", F(0.1)),
        ("MPC_JERK_AUTO", F(4.0)),
        // Position mode (multicopter_position_mode_params.c, v1.16 defaults).
        ("MPC_JERK_MAX", F(8.0)),
        ("MPC_LAND_ALT1", F(10.0)),
        ("MPC_LAND_ALT2", F(5.0)),
        ("MPC_LAND_SPEED", F(0.7)),
        ("MPC_MAN_Y_MAX", F(150.0)),
        ("MPC_POS_MODE", I(4)),
        ("MPC_THR_HOVER", F(0.5)),
        ("MPC_THR_MIN", F(0.12)),
        ("MPC_TKO_SPEED", F(1.5)),
        ("MPC_VEL_MANUAL", F(10.0)),
        ("MPC_XY_CRUISE", F(5.0)),
        ("MPC_XY_MAN_EXPO", F(0.6)),
        ("MPC_XY_P", F(0.95)),
        ("MPC_XY_VEL_I_ACC", F(0.4)),
        ("MPC_XY_VEL_MAX", F(12.0)),
        ("MPC_XY_VEL_P_ACC", F(1.8)),
        ("MPC_YAWRAUTO_MAX", F(45.0)),
        ("MPC_YAW_EXPO", F(0.6)),
        ("MPC_YAW_MODE", I(0)),
        ("MPC_Z_MAN_EXPO", F(0.6)),
        ("MPC_Z_P", F(1.0)),
        ("MPC_Z_VEL_I_ACC", F(2.0)),
        ("MPC_Z_VEL_MAX_DN", F(1.5)),
        ("MPC_Z_VEL_MAX_UP", F(3.0)),
        ("MPC_Z_VEL_P_ACC", F(4.0)),
        ("NAV_ACC_RAD", F(10.0)),
        ("NAV_DLL_ACT", I(0)),
        ("NAV_MC_ALT_RAD", F(0.8)),
        ("NAV_RCL_ACT", I(2)),
        ("RTL_DESCEND_ALT", F(30.0)),
        ("RTL_RETURN_ALT", F(60.0)),
        ("SDLOG_PROFILE", I(1)),
        ("SYS_AUTOSTART", I(10040)),
        // 1 on a board flown in the loop (HITL); the mock is SITL.
        ("SYS_HITL", I(0)),
    ]
};

/// The parameter table: names in PX4's sorted order, index = position.
#[derive(Debug, Clone)]
pub struct ParamTable {
    entries: Vec<(&'static str, ParamValue)>,
    version: u64,
}

impl Default for ParamTable {
    fn default() -> Self {
        Self {
            entries: DEFAULTS.to_vec(),
            version: 0,
        }
    }
}

/// What a PARAM_* message asks the vehicle to send back.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamReply {
    /// Send these PARAM_VALUE messages.
    Values(Vec<MavMessage>),
    /// Send a STATUSTEXT (e.g. unknown parameter).
    Text(MavSeverity, String),
}

impl ParamTable {
    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when the table is empty (never, for the PX4 table).
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Incremented on every successful set; lets users cache derived values.
    pub fn version(&self) -> u64 {
        self.version
    }

    /// Value by name.
    pub fn get(&self, name: &str) -> Option<ParamValue> {
        self.index_of(name).map(|i| self.entries[i].1)
    }

    /// Value by name as f64; 0 for unknown names (only used with names from `DEFAULTS`).
    pub fn f64(&self, name: &str) -> f64 {
        self.get(name).map_or(0.0, ParamValue::as_f64)
    }

    /// Set by name, keeping the declared type (a value of the other type is converted
    /// numerically). Returns false for unknown names.
    pub fn set(&mut self, name: &str, value: ParamValue) -> bool {
        let Some(i) = self.index_of(name) else {
            return false;
        };
        let slot = &mut self.entries[i].1;
        *slot = match (*slot, value) {
            (ParamValue::Int(_), ParamValue::Float(f)) => ParamValue::Int(f.round() as i32),
            (ParamValue::Float(_), ParamValue::Int(v)) => ParamValue::Float(v as f32),
            (_, v) => v,
        };
        self.version += 1;
        true
    }

    /// Removes `name` (a parameter this PX4 release does not have); whether it was there.
    pub fn remove(&mut self, name: &str) -> bool {
        let Some(i) = self.index_of(name) else {
            return false;
        };
        self.entries.remove(i);
        true
    }

    fn index_of(&self, name: &str) -> Option<usize> {
        self.entries.iter().position(|(n, _)| *n == name)
    }

    fn value_msg(&self, index: usize) -> Option<MavMessage> {
        let (name, value) = self.entries.get(index)?;
        let (param_value, param_type) = value.to_wire();
        Some(MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
            param_value,
            param_count: self.entries.len() as u16,
            param_index: index as u16,
            param_id: (*name).into(),
            param_type,
        }))
    }

    /// PARAM_REQUEST_LIST: every parameter.
    pub fn on_request_list(&self) -> ParamReply {
        ParamReply::Values((0..self.entries.len()).filter_map(|i| self.value_msg(i)).collect())
    }

    /// PARAM_REQUEST_READ: by index, or by name when index is -1.
    pub fn on_request_read(&self, req: &PARAM_REQUEST_READ_DATA) -> ParamReply {
        let index = if req.param_index >= 0 {
            Some(req.param_index as usize)
        } else {
            self.index_of(req.param_id.to_str().unwrap_or(""))
        };
        match index.and_then(|i| self.value_msg(i)) {
            Some(m) => ParamReply::Values(vec![m]),
            None => unknown(req.param_id.to_str().unwrap_or("?")),
        }
    }

    /// PARAM_SET: decode bytewise per the sender's declared type, store, echo PARAM_VALUE.
    pub fn on_set(&mut self, set: &PARAM_SET_DATA) -> ParamReply {
        let name = set.param_id.to_str().unwrap_or("").to_string();
        let value = match set.param_type {
            MavParamType::MAV_PARAM_TYPE_INT32
            | MavParamType::MAV_PARAM_TYPE_UINT32
            | MavParamType::MAV_PARAM_TYPE_INT16
            | MavParamType::MAV_PARAM_TYPE_UINT16
            | MavParamType::MAV_PARAM_TYPE_INT8
            | MavParamType::MAV_PARAM_TYPE_UINT8 => ParamValue::Int(set.param_value.to_bits() as i32),
            _ if set.param_value.is_finite() => ParamValue::Float(set.param_value),
            _ => {
                return ParamReply::Text(
                    MavSeverity::MAV_SEVERITY_ERROR,
                    format!("[pm] invalid value for {name}"),
                );
            }
        };
        if !self.set(&name, value) {
            return unknown(&name);
        }
        match self.index_of(&name).and_then(|i| self.value_msg(i)) {
            Some(m) => ParamReply::Values(vec![m]),
            None => unknown(&name),
        }
    }
}

fn unknown(name: &str) -> ParamReply {
    ParamReply::Text(MavSeverity::MAV_SEVERITY_ERROR, format!("[pm] unknown param: {name}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set_msg(name: &str, value: f32, ty: MavParamType) -> PARAM_SET_DATA {
        PARAM_SET_DATA {
            param_value: value,
            target_system: 1,
            target_component: 1,
            param_id: name.into(),
            param_type: ty,
        }
    }

    #[test]
    fn int_params_travel_bytewise() {
        let t = ParamTable::default();
        let ParamReply::Values(v) = t.on_request_list() else {
            panic!("expected values")
        };
        assert_eq!(v.len(), t.len());
        let found = v.iter().find_map(|m| match m {
            MavMessage::PARAM_VALUE(p) if p.param_id.to_str().ok() == Some("GF_ACTION") => Some(p.clone()),
            _ => None,
        });
        let p = found.expect("GF_ACTION listed");
        assert_eq!(p.param_type, MavParamType::MAV_PARAM_TYPE_INT32);
        assert_eq!(p.param_value.to_bits() as i32, 2);
    }

    #[test]
    fn set_int_and_float() {
        let mut t = ParamTable::default();
        let r = t.on_set(&set_msg(
            "COM_OBS_AVOID",
            f32::from_bits(1),
            MavParamType::MAV_PARAM_TYPE_INT32,
        ));
        assert!(matches!(r, ParamReply::Values(_)));
        assert_eq!(t.get("COM_OBS_AVOID"), Some(ParamValue::Int(1)));
        t.on_set(&set_msg("NAV_ACC_RAD", 0.5, MavParamType::MAV_PARAM_TYPE_REAL32));
        assert_eq!(t.get("NAV_ACC_RAD"), Some(ParamValue::Float(0.5)));
        // A float sent for an int param is converted, not reinterpreted.
        t.on_set(&set_msg("GF_ACTION", 3.0, MavParamType::MAV_PARAM_TYPE_REAL32));
        assert_eq!(t.get("GF_ACTION"), Some(ParamValue::Int(3)));
        assert_eq!(t.version(), 3);
    }

    #[test]
    fn unknown_and_bad_values_are_reported() {
        let mut t = ParamTable::default();
        let r = t.on_set(&set_msg("NOPE", 1.0, MavParamType::MAV_PARAM_TYPE_REAL32));
        assert!(matches!(r, ParamReply::Text(_, ref s) if s.contains("NOPE")));
        let r = t.on_set(&set_msg("NAV_ACC_RAD", f32::NAN, MavParamType::MAV_PARAM_TYPE_REAL32));
        assert!(matches!(r, ParamReply::Text(..)));
        let r = t.on_request_read(&PARAM_REQUEST_READ_DATA {
            param_index: 999,
            ..Default::default()
        });
        assert!(matches!(r, ParamReply::Text(..)));
        let r = t.on_request_read(&PARAM_REQUEST_READ_DATA {
            param_index: -1,
            param_id: "NAV_ACC_RAD".into(),
            ..Default::default()
        });
        assert!(matches!(r, ParamReply::Values(ref v) if v.len() == 1));
    }
}
