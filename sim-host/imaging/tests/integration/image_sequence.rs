//! Image sequences (the camera issue's reader, shared with PIV): ordering by the number in the
//! file name, glob and multi-page TIFF, PNG/TIFF/BMP in 8 and 16 bits and RGB, and every
//! refusal naming the file and the reason.

use std::path::Path;

use sandjumper_imaging::frame::{GrayFrame, Pixels};
use sandjumper_imaging::render::write_png;
use sandjumper_imaging::sequence::ImageSequence;

fn gray8(w: u32, h: u32, seed: u8) -> GrayFrame {
    let px = (0..w * h)
        .map(|i| (i as u8).wrapping_mul(7).wrapping_add(seed))
        .collect();
    GrayFrame::from_u8(w, h, px).unwrap()
}

fn gray16(w: u32, h: u32) -> GrayFrame {
    let px = (0..w * h).map(|i| (i * 257 + 3) as u16).collect();
    GrayFrame::from_u16(w, h, px).unwrap()
}

fn read_all(seq: &ImageSequence) -> Vec<(u64, GrayFrame)> {
    seq.frames()
        .map(|f| f.map(|f| (f.number, f.frame)))
        .collect::<Result<_, _>>()
        .unwrap()
}

fn err_of(spec: &Path) -> String {
    match ImageSequence::open(spec.to_str().unwrap()) {
        Err(e) => e.to_string(),
        Ok(seq) => match seq.frames().find_map(Result::err) {
            Some(e) => e.to_string(),
            None => panic!("{} was accepted", spec.display()),
        },
    }
}

#[test]
fn a_directory_is_ordered_by_the_number_in_the_names_not_lexically() {
    let dir = tempfile::tempdir().unwrap();
    for (n, seed) in [(100, 3), (9, 1), (10, 2)] {
        write_png(
            &gray8(8, 6, seed),
            &dir.path().join(format!("frame_{n}.png")),
        )
        .unwrap();
    }
    std::fs::write(dir.path().join("notes.txt"), "not a frame").unwrap();
    let seq = ImageSequence::open(dir.path().to_str().unwrap()).unwrap();
    assert_eq!(seq.numbers(), vec![9, 10, 100]);
    let frames = read_all(&seq);
    assert_eq!(frames[0].1, gray8(8, 6, 1));
    assert_eq!(frames[2].1, gray8(8, 6, 3));
    // A glob picks the same frames.
    let pattern = format!("{}/frame_*.png", dir.path().display());
    assert_eq!(
        ImageSequence::open(&pattern).unwrap().numbers(),
        vec![9, 10, 100]
    );
}

#[test]
fn sixteen_bit_png_rgb_bmp_and_tiff_pages_read_back() {
    let dir = tempfile::tempdir().unwrap();
    // 16-bit PNG: exact.
    let p16 = dir.path().join("deep_1.png");
    write_png(&gray16(5, 4), &p16).unwrap();
    let seq = ImageSequence::open(p16.to_str().unwrap()).unwrap();
    assert_eq!(read_all(&seq)[0].1, gray16(5, 4));
    // RGB: BT.601 luma, 0.299 R + 0.587 G + 0.114 B = 140.75 -> 141.
    let rgb = image::RgbImage::from_pixel(3, 2, image::Rgb([100, 150, 200]));
    let prgb = dir.path().join("colour_1.png");
    rgb.save(&prgb).unwrap();
    let f = &read_all(&ImageSequence::open(prgb.to_str().unwrap()).unwrap())[0].1;
    assert!(matches!(f.pixels(), Pixels::Eight(p) if p.iter().all(|&v| v == 141)));
    // BMP (8-bit grey).
    let bmp = dir.path().join("b_2.bmp");
    let g = image::GrayImage::from_fn(4, 3, |x, y| image::Luma([(x * 40 + y * 7) as u8]));
    g.save(&bmp).unwrap();
    let f = &read_all(&ImageSequence::open(bmp.to_str().unwrap()).unwrap())[0].1;
    for y in 0..3 {
        for x in 0..4 {
            assert_eq!(f.get(x, y), (x * 40 + y * 7) as f32);
        }
    }
    // Multi-page TIFF: one frame per page, numbered by page.
    let tif = dir.path().join("stack.tif");
    {
        let file = std::fs::File::create(&tif).unwrap();
        let mut enc = tiff::encoder::TiffEncoder::new(file).unwrap();
        for seed in 0..3u8 {
            let frame = gray8(6, 5, seed);
            let Pixels::Eight(px) = frame.pixels() else {
                unreachable!()
            };
            enc.write_image::<tiff::encoder::colortype::Gray8>(6, 5, px)
                .unwrap();
        }
    }
    let seq = ImageSequence::open(tif.to_str().unwrap()).unwrap();
    assert_eq!(seq.len(), 3);
    let frames = read_all(&seq);
    assert_eq!(
        frames.iter().map(|f| f.0).collect::<Vec<_>>(),
        vec![0, 1, 2]
    );
    assert_eq!(frames[2].1, gray8(6, 5, 2));
    assert_eq!(seq.nth(1).unwrap().unwrap().frame, gray8(6, 5, 1));
}

#[test]
fn bad_sequences_are_refused_naming_the_file_and_the_reason() {
    let root = tempfile::tempdir().unwrap();
    let mk = |name: &str| {
        let d = root.path().join(name);
        std::fs::create_dir(&d).unwrap();
        d
    };
    // Empty.
    let empty = mk("empty");
    assert!(err_of(&empty).contains("no frames"), "{}", err_of(&empty));
    // Truncated file.
    let trunc = mk("trunc");
    write_png(&gray8(64, 64, 0), &trunc.join("f_1.png")).unwrap();
    let full = std::fs::read(trunc.join("f_1.png")).unwrap();
    std::fs::write(trunc.join("f_2.png"), &full[..full.len() / 2]).unwrap();
    let e = err_of(&trunc);
    assert!(e.contains("f_2.png") && e.contains("cannot decode"), "{e}");
    // Not an image at all.
    let junk = mk("junk");
    std::fs::write(junk.join("f_1.png"), b"hello").unwrap();
    assert!(err_of(&junk).contains("f_1.png"), "{}", err_of(&junk));
    // Mixed sizes.
    let sizes = mk("sizes");
    write_png(&gray8(8, 6, 0), &sizes.join("f_1.png")).unwrap();
    write_png(&gray8(8, 7, 0), &sizes.join("f_2.png")).unwrap();
    let e = err_of(&sizes);
    assert!(
        e.contains("f_2.png") && e.contains("8x7 differs from 8x6"),
        "{e}"
    );
    // Bit depth changing mid-sequence.
    let depth = mk("depth");
    write_png(&gray8(5, 4, 0), &depth.join("f_1.png")).unwrap();
    write_png(&gray16(5, 4), &depth.join("f_2.png")).unwrap();
    let e = err_of(&depth);
    assert!(
        e.contains("f_2.png") && e.contains("bit depth 16 differs from 8"),
        "{e}"
    );
    // Two files with one number; a name without a number.
    let dup = mk("dup");
    write_png(&gray8(5, 4, 0), &dup.join("a_1.png")).unwrap();
    write_png(&gray8(5, 4, 0), &dup.join("b_001.png")).unwrap();
    assert!(err_of(&dup).contains("frame number 1"), "{}", err_of(&dup));
    let nonum = mk("nonum");
    write_png(&gray8(5, 4, 0), &nonum.join("first.png")).unwrap();
    assert!(
        err_of(&nonum).contains("no frame number"),
        "{}",
        err_of(&nonum)
    );
    // Nothing there; a glob matching nothing.
    assert!(err_of(&root.path().join("absent")).contains("no such file"));
    let none = root.path().join("empty/*.png");
    assert!(err_of(&none).contains("matches no file"));
}
