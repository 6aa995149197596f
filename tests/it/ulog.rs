//! A minimal ULog writer for fixtures (ULog spec: header, flag bits, format, add-logged, data), so the
//! third-party parser behind `score` is exercised on files built here from first principles.

pub struct ULogWriter {
    bytes: Vec<u8>,
}

impl ULogWriter {
    pub fn new() -> Self {
        let mut bytes = b"ULog\x01\x12\x35".to_vec();
        bytes.push(1); // version
        bytes.extend_from_slice(&0u64.to_le_bytes());
        let mut w = Self { bytes };
        w.message(b'B', &[0u8; 40]); // flag bits: no compat/incompat flags, no appended data
        w
    }

    fn message(&mut self, kind: u8, payload: &[u8]) {
        self.bytes.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        self.bytes.push(kind);
        self.bytes.extend_from_slice(payload);
    }

    /// Declares `vehicle_local_position` (a subset of PX4's fields) as message id 0.
    pub fn local_position_format(mut self) -> Self {
        let fmt = b"vehicle_local_position:uint64_t timestamp;float x;float y;float z;float heading;";
        self.message(b'F', fmt);
        let mut add = vec![0u8]; // multi id
        add.extend_from_slice(&0u16.to_le_bytes());
        add.extend_from_slice(b"vehicle_local_position");
        self.message(b'A', &add);
        self
    }

    /// One sample: time in microseconds, NED position (z down), heading in radians.
    pub fn sample(mut self, t_us: u64, x: f32, y: f32, z_down: f32, heading: f32) -> Self {
        let mut d = 0u16.to_le_bytes().to_vec();
        d.extend_from_slice(&t_us.to_le_bytes());
        for v in [x, y, z_down, heading] {
            d.extend_from_slice(&v.to_le_bytes());
        }
        self.message(b'D', &d);
        self
    }

    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }
}
