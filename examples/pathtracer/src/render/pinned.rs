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

/// As above with 5 samples per pixel: four paths traced together (as at every task's default
/// spp, a multiple of four) and one alone. The hashes are those of the renderer before the
/// paths' rays were tested in lanes (`--target --scale 0.5 --spp 5 --seed 7`).
#[test]
fn task_images_with_paths_in_flight_together_are_pinned() {
    let expected = [
        ("cup", 0xbcfb_5dc9_89c4_cef7),
        ("shadow", 0xd675_7643_2ff3_672f),
        ("occlusion", 0x0969_f577_6234_031f),
        ("gi", 0x8b61_388a_9743_7f67),
        ("sort", 0x7eab_d26f_7574_58ed),
        ("caustic", 0x3aa9_b839_00f0_6dad),
        ("texture", 0x6420_8b9a_f18b_e2c0),
    ];
    let view = View {
        scale: Some(0.5),
        ..View::default()
    };
    for (task, (name, hash)) in tasks::all().into_iter().zip(expected) {
        assert_eq!(task.name(), name);
        let image = task.render(&task.target(), 7, 5, view);
        assert_eq!(fnv1a(&image.data), hash, "{name}: the image changed");
    }
}
