//! Target `store`: the parameter store with power cuts at arbitrary
//! program/erase steps.

use embedded_storage::nor_flash::NorFlash;
use imu_emu::nor::RamNor;
use imu_emu::store::{ImageSpec, ParamStore, KERNEL_IMAGE};

use crate::script::Cursor;

/// A 301-byte second image (the shape of the ISB FLASH_CONFIG one).
const OTHER: ImageSpec = ImageSpec {
    len: 301,
    magic: *b"ISBC",
    version: 1,
};

/// One store's expectations.
struct StoreTrack {
    store: ParamStore<ImageSpec>,
    /// What loads (the newest complete save; `None` before the first).
    current: Option<Vec<u8>>,
}

fn load_image<F: NorFlash>(s: &ParamStore<ImageSpec>, flash: &mut F) -> Option<Vec<u8>> {
    let mut out = vec![0; usize::from(s.spec().len)];
    s.load(flash, &mut out)
        .expect("a powered flash loads")
        .then_some(out)
}

/// The parameter store with power cuts at arbitrary program/erase steps
/// (half-done or torn): two stores (the KERNEL block at 0, a 301-byte image
/// at 8192) in one flash; each op saves an image derived from the input to
/// one of them, maybe cut. After every op: a completed (`Ok`) save loads;
/// a cut one loads the previous image or the new one, never anything
/// else, never older than the last completed save; the other store is
/// untouched.
pub fn store(data: &[u8]) {
    let mut c = Cursor::new(data);
    let mut flash = RamNor::<16384>::new();
    let mut tracks = [
        StoreTrack {
            store: ParamStore::for_image(0, KERNEL_IMAGE),
            current: None,
        },
        StoreTrack {
            store: ParamStore::for_image(8192, OTHER),
            current: None,
        },
    ];
    while !c.is_empty() {
        let op = c.u8();
        let which = usize::from(op & 1);
        let t = &tracks[which];
        let len = usize::from(t.store.spec().len);
        // The new image: the current one with some bytes changed.
        let mut image = t.current.clone().unwrap_or_else(|| vec![0xFF; len]);
        for _ in 0..(op >> 1) % 8 {
            let at = usize::from(c.u16()) % len;
            image[at] = c.u8();
        }
        let cut = c.u16();
        let torn = c.u32();
        match cut % 4 {
            0 => {}
            1 => flash.cut_power_after(u32::from(cut >> 2)),
            _ => flash.cut_power_torn(u32::from(cut >> 2), torn),
        }
        let r = tracks[which].store.save(&mut flash, &image);
        let was_cut = flash.power_lost();
        flash.restore_power();
        assert_eq!(r.is_ok(), !was_cut, "Ok iff the save ran to the end");
        for (i, t) in tracks.iter_mut().enumerate() {
            let got = load_image(&t.store, &mut flash);
            if i != which {
                assert_eq!(got, t.current, "the other store changed");
            } else if r.is_ok() {
                assert_eq!(got.as_ref(), Some(&image), "a completed save loads");
            } else {
                assert!(
                    got == t.current || got.as_ref() == Some(&image),
                    "a cut save loaded neither the old nor the new image"
                );
            }
            t.current = got;
        }
    }
}
