//! The renderer's images pinned bit for bit: speed work must not change a single value.
//!
//! The committed results (optimisation traces, figures, the agreement with Mitsuba) are
//! reproducible only while every render draws the same bits. Each task's target, at half its
//! resolution, 3 samples per pixel (an odd count: paths traced in pairs and the one left
//! over) and seed 7, is hashed (FNV-1a over the values' bits, row by row, R G B); the hashes
//! are those of the renderer the committed results were made with (the EXR the `render`
//! command writes, `--target --scale 0.5 --spp 3 --seed 7`).

use crate::tasks::{self, View};

/// FNV-1a (64 bits) of the image's values as bits, in memory order.
fn fnv1a(values: &[f32]) -> u64 {
    values.iter().fold(0xcbf2_9ce4_8422_2325, |h, v| {
        (h ^ u64::from(v.to_bits())).wrapping_mul(0x0100_0000_01b3)
    })
}

#[test]
fn task_images_are_those_of_the_renderer_before_the_speed_work() {
    let expected = [
        ("cup", 0xe1d7_2c7f_dc84_e6e8),
        ("shadow", 0x4f0e_5e08_38c0_c25b),
        ("occlusion", 0xcfe6_ffdd_e182_af0e),
        ("gi", 0xb67c_5f65_d26e_f00b),
        ("sort", 0x8776_de80_0171_80cf),
        ("caustic", 0x20d7_a255_e919_7a6d),
        ("texture", 0x9fcc_35c6_eeab_23ca),
    ];
    let view = View {
        scale: Some(0.5),
        ..View::default()
    };
    for (task, (name, hash)) in tasks::all().into_iter().zip(expected) {
        assert_eq!(task.name(), name);
        let image = task.render(&task.target(), 7, 3, view);
        assert_eq!(fnv1a(&image.data), hash, "{name}: the image changed");
    }
}

/// As above with 13 samples per pixel: eight paths traced together, then four, then one alone
/// (every task's default spp is a multiple of four). The hashes are those of the renderer
/// before the paths' rays were tested in lanes (`--target --scale 0.5 --spp 13 --seed 7`).
#[test]
fn task_images_with_paths_in_flight_together_are_pinned() {
    let expected = [
        ("cup", 0xc49d_8f1f_6c1c_3fb4),
        ("shadow", 0x27ed_82cd_245e_58a5),
        ("occlusion", 0x3430_ce41_2ae6_68e4),
        ("gi", 0x7403_fb37_89f0_f6aa),
        ("sort", 0xe20e_4206_e0fb_65fb),
        ("caustic", 0xf20d_632a_6612_7d08),
        ("texture", 0x9ea0_e6e1_ac47_e442),
    ];
    let view = View {
        scale: Some(0.5),
        ..View::default()
    };
    for (task, (name, hash)) in tasks::all().into_iter().zip(expected) {
        assert_eq!(task.name(), name);
        let image = task.render(&task.target(), 7, 13, view);
        assert_eq!(fnv1a(&image.data), hash, "{name}: the image changed");
    }
}
