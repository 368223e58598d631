//! One declaration per ISB data set: [`crate::data_set!`] turns a list of typed
//! fields with their byte offsets into the offset constants, the size, the
//! struct and its encoder and decoder, and checks at compile time that the
//! offsets are those of the packed C struct (each field starts where the
//! previous one ends, the last ends at the size). The model is the ublox
//! crate's packet definitions; the layouts are the SDK's (`data_sets.h`,
//! `docs/isb-data-sets.md`).

/// A packed little-endian field type of an ISB struct.
pub trait Field: Sized + Copy {
    /// Bytes it takes.
    const LEN: usize;
    /// Writes `self` at `off` of `b` (nothing when it does not fit).
    fn put(&self, b: &mut [u8], off: usize);
    /// Reads the field at `off` of `b` (zeros when out of range).
    fn get(b: &[u8], off: usize) -> Self;
}

macro_rules! scalar_field {
    ($($t:ty),*) => {$(
        impl Field for $t {
            const LEN: usize = core::mem::size_of::<$t>();
            fn put(&self, b: &mut [u8], off: usize) {
                super::sets::le::put(b, off, &self.to_le_bytes());
            }
            fn get(b: &[u8], off: usize) -> Self {
                <$t>::from_le_bytes(super::sets::le::get(b, off))
            }
        }
    )*};
}
scalar_field!(u8, i8, u16, i16, u32, i32, u64, f32, f64);

impl<T: Field + Default, const N: usize> Field for [T; N] {
    const LEN: usize = N * T::LEN;
    fn put(&self, b: &mut [u8], off: usize) {
        for (i, x) in self.iter().enumerate() {
            x.put(b, off + i * T::LEN);
        }
    }
    fn get(b: &[u8], off: usize) -> Self {
        let mut out = [T::default(); N];
        for (i, x) in out.iter_mut().enumerate() {
            *x = T::get(b, off + i * T::LEN);
        }
        out
    }
}

/// Declares one packed ISB struct (module doc):
///
/// ```text
/// data_set! {
///     /// doc
///     #[derive(...)]
///     pub struct Name in mod name, SIZE bytes {
///         /// doc
///         field: type = OFFSET_NAME @ offset,
///         ...
///     }
///     extra items of `mod name`
/// }
/// ```
///
/// gives `mod name` with `SIZE` and one `OFFSET_NAME` per field (plus the
/// extra items), `struct Name` with `encode(&self) -> [u8; SIZE]` and
/// `decode(&[u8; SIZE]) -> Self`, and `Name` as a [`Field`] (so one struct
/// nests in another, as `imu_mag_t` holds an `imu_t`). A layout whose
/// offsets leave a gap, overlap or do not add up to the size does not
/// compile.
#[macro_export]
macro_rules! data_set {
    (
        $(#[$meta:meta])*
        pub struct $name:ident in mod $m:ident, $size:literal bytes {
            $( $(#[$fmeta:meta])* $field:ident : $ty:ty = $OFF:ident @ $off:literal ),* $(,)?
        }
        $($extra:item)*
    ) => {
        #[doc = concat!("Byte layout of [`", stringify!($name), "`]: `SIZE` and one offset per field.")]
        pub mod $m {
            /// Struct size, bytes.
            pub const SIZE: usize = $size;
            $(
                #[doc = concat!("Offset of `", stringify!($field), "`.")]
                pub const $OFF: usize = $off;
            )*
            $($extra)*
        }

        $(#[$meta])*
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }

        // The packed C layout: contiguous fields, total = size.
        const _: () = {
            let mut at = 0usize;
            $(
                assert!(at == $off, concat!("gap or overlap before ", stringify!($field)));
                at += <$ty as $crate::isb::layout::Field>::LEN;
            )*
            assert!(at == $size, concat!(stringify!($name), ": fields do not add up to its size"));
        };

        impl $name {
            /// The image.
            pub fn encode(&self) -> [u8; $m::SIZE] {
                let mut b = [0u8; $m::SIZE];
                $( $crate::isb::layout::Field::put(&self.$field, &mut b, $m::$OFF); )*
                b
            }
            /// Decodes an image.
            pub fn decode(b: &[u8; $m::SIZE]) -> Self {
                $name {
                    $( $field: <$ty as $crate::isb::layout::Field>::get(b, $m::$OFF), )*
                }
            }
        }

        impl $crate::isb::layout::Field for $name {
            const LEN: usize = $m::SIZE;
            fn put(&self, b: &mut [u8], off: usize) {
                $crate::isb::sets::le::put(b, off, &self.encode());
            }
            fn get(b: &[u8], off: usize) -> Self {
                Self::decode(&$crate::isb::sets::le::get(b, off))
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::Field;

    crate::data_set! {
        /// A test layout.
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub struct Probe in mod probe, 15 bytes {
            /// A byte.
            a: u8 = A @ 0,
            /// Two halves.
            b: [i16; 2] = B @ 1,
            /// A double.
            c: f64 = C @ 5,
            /// A short.
            d: u16 = D @ 13,
        }
    }

    #[test]
    fn offsets_and_bytes_follow_the_declaration() {
        let p = Probe {
            a: 7,
            b: [-2, 3],
            c: 1.5,
            d: 0xBEEF,
        };
        let b = p.encode();
        assert_eq!(probe::SIZE, 15);
        assert_eq!(b[0], 7);
        assert_eq!(&b[1..5], &[0xFE, 0xFF, 3, 0]);
        assert_eq!(&b[5..13], &1.5f64.to_le_bytes());
        assert_eq!(&b[13..15], &[0xEF, 0xBE]);
        assert_eq!(Probe::decode(&b), p);
        assert_eq!(<Probe as Field>::LEN, 15);
        // Out of range: zeros, nothing written.
        assert_eq!(u32::get(&b, 14), 0);
        let mut short = [0u8; 3];
        p.put(&mut short, 0);
        assert_eq!(short, [0; 3]);
    }
}
