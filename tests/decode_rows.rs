//! `LobeType::decode_rows` equals `decode` lane by lane, bit for bit, for every
//! registered lobe type: row copies (`Model::DECODE_COPIES`) only where decoding copies.

mod common;

use common::Rng;
use glint::params::{self, ParamKind};
use glint::registry::Registry;

#[test]
fn decode_rows_equal_decode_per_lane() {
    let registry = Registry::with_builtins();
    let mut rng = Rng::new(0xdec0);
    let len = 48;
    for lobe in registry.iter() {
        let specs = lobe.params();
        let (size, decoded_size) = (params::block_size(specs), lobe.decoded_len());
        let mut blocks = vec![vec![0.0f32; size]; len];
        for (j, block) in blocks.iter_mut().enumerate() {
            params::write_defaults(specs, block);
            for (i, spec) in specs.iter().enumerate() {
                let at = params::offset_of(specs, i);
                for v in &mut block[at..at + spec.kind.size()] {
                    *v = match spec.kind {
                        ParamKind::Enum => (j % spec.choices.len()) as f32,
                        _ => {
                            let (lo, hi) = (spec.min.max(-10.0), spec.max.min(10.0));
                            lo + (hi - lo) * rng.f32()
                        }
                    };
                }
            }
        }
        let mut rows = vec![0.0f32; size * len];
        for (j, block) in blocks.iter().enumerate() {
            for (p, &v) in block.iter().enumerate() {
                rows[p * len + j] = v;
            }
        }
        let mut decoded_rows = vec![f32::NAN; decoded_size * len];
        lobe.decode_rows(&rows, &mut decoded_rows, len);
        let mut decoded = vec![0.0f32; decoded_size];
        for (j, block) in blocks.iter().enumerate() {
            lobe.decode(block, &mut decoded);
            for (p, &v) in decoded.iter().enumerate() {
                assert_eq!(
                    v.to_bits(),
                    decoded_rows[p * len + j].to_bits(),
                    "{}: lane {j} value {p}",
                    lobe.name()
                );
            }
        }
    }
}
