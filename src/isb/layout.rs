//! One declaration per ISB data set: [`crate::data_set!`] turns a list of typed
//! fields with their byte offsets, and for the fields a host reads by name
//! their `data_sets.h` name and unit, into the offset constants, the size,
//! the struct, its encoder and decoder and its field table
//! ([`Field::FIELDS`], what `imu-emu client --protocol isb` and
//! `imu-emu isb-layouts` read). It checks at compile time that the offsets
//! are those of the packed C struct (each field starts where the previous
//! one ends, the last ends at the size) and that each named field's kind
//! fits its Rust type. The model is the ublox crate's packet definitions;
//! the layouts are the SDK's (`data_sets.h`, `docs/isb-data-sets.md`).

use super::sets::le;

/// A packed little-endian field type of an ISB struct.
pub trait Field: Sized + Copy {
    /// Bytes it takes.
    const LEN: usize;
    /// The kind a host reads it as, when the type alone says it (`f32` is
    /// [`Kind::F32`], `[f32; 3]` [`Kind::F32x3`]); `None` when a
    /// declaration must say it (a `[u8; 4]` version) or it has none (a
    /// struct, read by its own fields).
    const KIND: Option<Kind> = None;
    /// The named fields inside it, offsets from its start: a declared
    /// struct's table; an array's, those of its first element.
    const FIELDS: &'static [FieldSpec] = &[];
    /// Bytes from one element to the next (an array's element size; the
    /// type's own size otherwise).
    const STRIDE: usize = Self::LEN;
    /// Writes `self` at `off` of `b` (nothing when it does not fit).
    fn put(&self, b: &mut [u8], off: usize);
    /// Reads the field at `off` of `b` (zeros when out of range).
    fn get(b: &[u8], off: usize) -> Self;
}

macro_rules! scalar_field {
    ($($t:ty => $kind:expr),*) => {$(
        impl Field for $t {
            const LEN: usize = core::mem::size_of::<$t>();
            const KIND: Option<Kind> = $kind;
            fn put(&self, b: &mut [u8], off: usize) {
                le::put(b, off, &self.to_le_bytes());
            }
            fn get(b: &[u8], off: usize) -> Self {
                <$t>::from_le_bytes(le::get(b, off))
            }
        }
    )*};
}
scalar_field!(
    u8 => Some(Kind::U8),
    i8 => None,
    u16 => Some(Kind::U16),
    i16 => None,
    u32 => Some(Kind::U32),
    i32 => None,
    u64 => Some(Kind::U64),
    f32 => Some(Kind::F32),
    f64 => Some(Kind::F64)
);

impl<T: Field + Default, const N: usize> Field for [T; N] {
    const LEN: usize = N * T::LEN;
    const KIND: Option<Kind> = Kind::array_of(T::KIND, N);
    const FIELDS: &'static [FieldSpec] = T::FIELDS;
    const STRIDE: usize = T::LEN;
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

/// The type of a named field, as packed in the struct.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `u8`.
    U8,
    /// `u16`.
    U16,
    /// `u32`.
    U32,
    /// `u64`.
    U64,
    /// `f32`.
    F32,
    /// `f64`.
    F64,
    /// `f32[3]`.
    F32x3,
    /// `f32[4]` (a quaternion).
    F32x4,
    /// `f64[3]`.
    F64x3,
    /// `u8[4]` version `a.b.c.d`.
    Version,
    /// `char[24]`, NUL padded.
    Str24,
}

impl Kind {
    /// Bytes the field takes.
    pub const fn size(self) -> usize {
        match self {
            Kind::U8 => 1,
            Kind::U16 => 2,
            Kind::U32 | Kind::F32 | Kind::Version => 4,
            Kind::U64 | Kind::F64 => 8,
            Kind::F32x3 => 12,
            Kind::F32x4 => 16,
            Kind::F64x3 => 24,
            Kind::Str24 => 24,
        }
    }

    /// Its name in `imu-emu isb-layouts --json` and the Python table.
    pub const fn name(self) -> &'static str {
        match self {
            Kind::U8 => "u8",
            Kind::U16 => "u16",
            Kind::U32 => "u32",
            Kind::U64 => "u64",
            Kind::F32 => "f32",
            Kind::F64 => "f64",
            Kind::F32x3 => "f32x3",
            Kind::F32x4 => "f32x4",
            Kind::F64x3 => "f64x3",
            Kind::Version => "ver",
            Kind::Str24 => "str24",
        }
    }

    /// The kind of `[element; n]`: three or four `f32`, three `f64`, 24
    /// chars; `None` for any other array (a declaration says it).
    pub const fn array_of(element: Option<Kind>, n: usize) -> Option<Kind> {
        match (element, n) {
            (Some(Kind::F32), 3) => Some(Kind::F32x3),
            (Some(Kind::F32), 4) => Some(Kind::F32x4),
            (Some(Kind::F64), 3) => Some(Kind::F64x3),
            (Some(Kind::U8), 24) => Some(Kind::Str24),
            _ => None,
        }
    }

    /// The kind of a field of type `T` (compile-time error when the type
    /// does not say it).
    pub const fn of<T: Field>() -> Kind {
        match T::KIND {
            Some(k) => k,
            None => panic!("a named field's type has no kind of its own: declare it with `as`"),
        }
    }

    /// `self` for a field of type `T`, checked: a kind the declaration
    /// gives must take the type's bytes (compile-time error otherwise).
    pub const fn checked<T: Field>(self) -> Kind {
        assert!(
            self.size() == T::LEN,
            "a declared kind does not fit its field's type"
        );
        self
    }
}

/// One named field of a data set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldSpec {
    /// Its `data_sets.h` name (`startupNavDtMs`).
    pub name: &'static str,
    /// Byte offset in the struct.
    pub offset: usize,
    /// Type.
    pub kind: Kind,
    /// Unit of the value (`""` for none).
    pub unit: &'static str,
}

/// A field's value as read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// An unsigned integer.
    Unsigned(u64),
    /// A float.
    Float(f64),
    /// Three floats (x, y, z).
    Vec3([f64; 3]),
    /// Four floats (a quaternion w, x, y, z).
    Vec4([f64; 4]),
    /// A version `a.b.c.d`.
    Version([u8; 4]),
    /// NUL-padded text: the bytes, and the length up to the first NUL.
    Text([u8; 24], usize),
}

/// Reads `spec` from a data set image `b` (zeros past its end).
pub fn read(spec: &FieldSpec, b: &[u8]) -> Value {
    let o = spec.offset;
    match spec.kind {
        Kind::U8 => Value::Unsigned(u64::from(le::get::<1>(b, o)[0])),
        Kind::U16 => Value::Unsigned(u64::from(le::u16(b, o))),
        Kind::U32 => Value::Unsigned(u64::from(le::u32(b, o))),
        Kind::U64 => Value::Unsigned(le::u64(b, o)),
        Kind::F32 => Value::Float(f64::from(le::f32(b, o))),
        Kind::F64 => Value::Float(le::f64(b, o)),
        Kind::F32x3 => Value::Vec3(le::f32x3(b, o).map(f64::from)),
        Kind::F32x4 => Value::Vec4([0, 4, 8, 12].map(|i| f64::from(le::f32(b, o + i)))),
        Kind::F64x3 => Value::Vec3([le::f64(b, o), le::f64(b, o + 8), le::f64(b, o + 16)]),
        Kind::Version => Value::Version(le::get::<4>(b, o)),
        Kind::Str24 => {
            let s = le::get::<24>(b, o);
            let n = s.iter().position(|&c| c == 0).unwrap_or(24);
            Value::Text(s, n)
        }
    }
}

// ---- the const functions the declarations' field tables are built with ----

const PLACEHOLDER: FieldSpec = FieldSpec {
    name: "",
    offset: 0,
    kind: Kind::U8,
    unit: "",
};

const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The field called `name` of `fields` (compile-time error when none is).
#[doc(hidden)]
pub const fn named(fields: &[FieldSpec], name: &str) -> FieldSpec {
    let mut i = 0;
    while i < fields.len() {
        if same(fields[i].name, name) {
            return fields[i];
        }
        i += 1;
    }
    panic!("no field of that name in the nested struct")
}

/// `spec` renamed `name` and moved by `by` bytes.
#[doc(hidden)]
pub const fn moved(spec: FieldSpec, name: &'static str, by: usize) -> FieldSpec {
    FieldSpec {
        name,
        offset: spec.offset + by,
        ..spec
    }
}

/// The fields of a nested struct moved to its offset `by`, each renamed
/// per `renames` (`(its name, the name here)`; a rename of a field the
/// struct does not name fails to compile).
#[doc(hidden)]
pub const fn nested<const N: usize>(
    fields: &[FieldSpec],
    by: usize,
    renames: &[(&str, &'static str)],
) -> [FieldSpec; N] {
    let mut r = 0;
    while r < renames.len() {
        let _ = named(fields, renames[r].0);
        r += 1;
    }
    let mut out = [PLACEHOLDER; N];
    let mut i = 0;
    while i < N {
        let mut name = fields[i].name;
        let mut r = 0;
        while r < renames.len() {
            if same(renames[r].0, name) {
                name = renames[r].1;
            }
            r += 1;
        }
        out[i] = moved(fields[i], name, by);
        i += 1;
    }
    out
}

/// The total length of `parts`.
#[doc(hidden)]
pub const fn total(parts: &[&[FieldSpec]]) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < parts.len() {
        n += parts[i].len();
        i += 1;
    }
    n
}

/// `parts` one after the other (`N` = [`total`]).
#[doc(hidden)]
pub const fn concat<const N: usize>(parts: &[&[FieldSpec]]) -> [FieldSpec; N] {
    let mut out = [PLACEHOLDER; N];
    let mut at = 0;
    let mut i = 0;
    while i < parts.len() {
        let mut j = 0;
        while j < parts[i].len() {
            out[at] = parts[i][j];
            at += 1;
            j += 1;
        }
        i += 1;
    }
    out
}

/// Declares one packed ISB struct (module doc):
///
/// ```text
/// data_set! {
///     /// doc
///     #[derive(...)]
///     pub struct Name in mod name, SIZE bytes {
///         /// doc
///         field: type = OFFSET_NAME @ offset => [naming],
///         _: type = OFFSET_NAME @ offset,       // reserved bytes
///         ...
///     }
///     extra items of `mod name`
/// }
/// ```
///
/// gives `mod name` with `SIZE`, one `OFFSET_NAME` per field and
/// `FIELDS` (plus the extra items), `struct Name` (every field but the
/// reserved `_` ones, which encode as zeros) with `encode(&self) -> [u8;
/// SIZE]` and `decode(&[u8; SIZE]) -> Self`, and `Name` as a [`Field`]
/// (so one struct nests in another, as `imu_mag_t` holds an `imu_t`). A
/// layout whose offsets leave a gap, overlap or do not add up to the size
/// does not compile.
///
/// The naming (`=> [...]`, absent for a field no host reads by name) puts
/// the field in the table:
/// - `["time" in "s"]`: its `data_sets.h` name and unit, its kind that of
///   its type ([`Field::KIND`]); `["hardwareVer" as Version]`: a kind the
///   type does not say, checked to take the type's bytes;
/// - `[..]`: a nested struct's named fields at their offsets here (of an
///   array of structs, the first element's); `[.. "time" => "magTime"]`
///   renames some;
/// - `[each "nmeaBroadcastMsgs" [0 1 2] ["msgID", "period"]]`: those
///   fields of elements 0, 1 and 2 of an array of structs, named
///   `nmeaBroadcastMsgs[0].msgID` ….
#[macro_export]
macro_rules! data_set {
    (
        $(#[$meta:meta])*
        pub struct $name:ident in mod $m:ident, $size:literal bytes {
            $($body:tt)*
        }
        $($extra:item)*
    ) => {
        $crate::__data_set! {
            @munch [ [$(#[$meta])*] $name $m $size ] [ $($extra)* ] [] []
            $($body)*
        }
    };
}

/// The parser behind [`crate::data_set!`]: one field at a time into the
/// struct's members and the layout's entries.
#[doc(hidden)]
#[macro_export]
macro_rules! __data_set {
    // Reserved bytes: an entry, no member.
    (@munch $head:tt $extra:tt [ $($mem:tt)* ] [ $($ent:tt)* ]
        $(#[$fmeta:meta])* _ : $ty:ty = $OFF:ident @ $off:literal $(, $($rest:tt)*)?
    ) => {
        $crate::__data_set! {
            @munch $head $extra [ $($mem)* ] [ $($ent)* { _ $ty, $OFF $off [] } ]
            $($($rest)*)?
        }
    };
    // A field.
    (@munch $head:tt $extra:tt [ $($mem:tt)* ] [ $($ent:tt)* ]
        $(#[$fmeta:meta])* $field:ident : $ty:ty = $OFF:ident @ $off:literal
        $(=> [ $($nm:tt)* ])? $(, $($rest:tt)*)?
    ) => {
        $crate::__data_set! {
            @munch $head $extra
            [ $($mem)* { [$(#[$fmeta])*] $field $ty, $OFF } ]
            [ $($ent)* { $field $ty, $OFF $off [ $($($nm)*)? ] } ]
            $($($rest)*)?
        }
    };
    // Every field read: the items.
    (@munch [ [$(#[$meta:meta])*] $name:ident $m:ident $size:literal ] [ $($extra:item)* ]
        [ $({ [$(#[$fmeta:meta])*] $field:ident $fty:ty, $FOFF:ident })* ]
        [ $({ $efield:tt $ety:ty, $OFF:ident $off:literal [ $($nm:tt)* ] })* ]
    ) => {
        #[doc = concat!("Byte layout of [`", stringify!($name), "`]: `SIZE`, one offset per field, the named fields.")]
        pub mod $m {
            /// Struct size, bytes.
            pub const SIZE: usize = $size;
            $(
                #[doc = concat!("Offset of `", stringify!($efield), "`.")]
                pub const $OFF: usize = $off;
            )*
            /// The fields a host reads by name (`data_sets.h` names).
            pub const FIELDS: &[$crate::isb::layout::FieldSpec] =
                <super::$name as $crate::isb::layout::Field>::FIELDS;
            $($extra)*
        }

        $(#[$meta])*
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $fty, )*
        }

        // The packed C layout: contiguous fields, total = size; and the
        // field table evaluated (a kind that does not fit fails here).
        const _: () = {
            let mut at = 0usize;
            $(
                assert!(at == $off, concat!("gap or overlap before ", stringify!($OFF)));
                at += <$ety as $crate::isb::layout::Field>::LEN;
            )*
            assert!(at == $size, concat!(stringify!($name), ": fields do not add up to its size"));
            let _ = <$name as $crate::isb::layout::Field>::FIELDS;
        };

        impl $name {
            /// The image.
            pub fn encode(&self) -> [u8; $m::SIZE] {
                let mut b = [0u8; $m::SIZE];
                $( $crate::isb::layout::Field::put(&self.$field, &mut b, $m::$FOFF); )*
                b
            }
            /// Decodes an image.
            pub fn decode(b: &[u8; $m::SIZE]) -> Self {
                $name {
                    $( $field: <$fty as $crate::isb::layout::Field>::get(b, $m::$FOFF), )*
                }
            }
        }

        impl $crate::isb::layout::Field for $name {
            const LEN: usize = $m::SIZE;
            const FIELDS: &'static [$crate::isb::layout::FieldSpec] = {
                const PARTS: &[&[$crate::isb::layout::FieldSpec]] = &[
                    $( &$crate::__field_part!($ety, $m::$OFF; $($nm)*), )*
                ];
                const N: usize = $crate::isb::layout::total(PARTS);
                const ALL: [$crate::isb::layout::FieldSpec; N] =
                    $crate::isb::layout::concat::<N>(PARTS);
                &ALL
            };
            fn put(&self, b: &mut [u8], off: usize) {
                $crate::isb::sets::le::put(b, off, &self.encode());
            }
            fn get(b: &[u8], off: usize) -> Self {
                Self::decode(&$crate::isb::sets::le::get(b, off))
            }
        }
    };
}

/// The table rows of one field of a [`crate::data_set!`] by its naming.
#[doc(hidden)]
#[macro_export]
macro_rules! __field_part {
    ($ty:ty, $off:expr;) => {
        [$crate::isb::layout::FieldSpec { name: "", offset: 0, kind: $crate::isb::layout::Kind::U8, unit: "" }; 0]
    };
    ($ty:ty, $off:expr; $name:literal $(in $unit:literal)?) => {
        [$crate::isb::layout::FieldSpec {
            name: $name,
            offset: $off,
            kind: $crate::isb::layout::Kind::of::<$ty>(),
            unit: $crate::__field_part!(@unit $($unit)?),
        }]
    };
    ($ty:ty, $off:expr; $name:literal as $kind:ident $(in $unit:literal)?) => {
        [$crate::isb::layout::FieldSpec {
            name: $name,
            offset: $off,
            kind: $crate::isb::layout::Kind::$kind.checked::<$ty>(),
            unit: $crate::__field_part!(@unit $($unit)?),
        }]
    };
    ($ty:ty, $off:expr; .. $($from:literal => $to:literal),*) => {
        $crate::isb::layout::nested::<{ <$ty as $crate::isb::layout::Field>::FIELDS.len() }>(
            <$ty as $crate::isb::layout::Field>::FIELDS,
            $off,
            &[$(($from, $to)),*],
        )
    };
    ($ty:ty, $off:expr; each $prefix:literal [$($i:literal)*] $subs:tt) => {
        $crate::isb::layout::concat::<{ [$($i),*].len() * $subs.len() }>(&[
            $( &$crate::__field_part!(@each $ty, $off, $prefix, $i, $subs), )*
        ])
    };
    (@each $ty:ty, $off:expr, $prefix:literal, $i:literal, [$($sub:literal),*]) => {
        [$(
            $crate::isb::layout::moved(
                $crate::isb::layout::named(<$ty as $crate::isb::layout::Field>::FIELDS, $sub),
                concat!($prefix, "[", $i, "].", $sub),
                $off + $i * <$ty as $crate::isb::layout::Field>::STRIDE,
            ),
        )*]
    };
    (@unit) => { "" };
    (@unit $unit:literal) => { $unit };
}

#[cfg(test)]
mod tests {
    use super::{Field, FieldSpec, Kind};
    use std::vec::Vec;

    crate::data_set! {
        /// A test layout.
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub struct Probe in mod probe, 15 bytes {
            /// A byte.
            a: u8 = A @ 0 => ["alpha"],
            /// Two halves.
            b: [i16; 2] = B @ 1,
            /// A double.
            c: f64 = C @ 5 => ["gamma" in "s"],
            /// A short.
            d: u16 = D @ 13,
        }
    }

    crate::data_set! {
        /// Probes nested: renamed, first element, each element.
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub struct Outer in mod outer, 35 bytes {
            /// Reserved.
            _: [u8; 5] = RESERVED @ 0,
            /// Nested, renamed.
            p: Probe = P @ 5 => [.. "gamma" => "time"],
            /// Two of them.
            q: [Probe; 1] = Q @ 20 => [each "q" [0] ["alpha"]],
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
        let names = |fs: &[FieldSpec]| {
            fs.iter()
                .map(|f| (f.name, f.offset, f.kind, f.unit))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            names(probe::FIELDS),
            [("alpha", 0, Kind::U8, ""), ("gamma", 5, Kind::F64, "s")]
        );
        assert_eq!(
            names(outer::FIELDS),
            [
                ("alpha", 5, Kind::U8, ""),
                ("time", 10, Kind::F64, "s"),
                ("q[0].alpha", 20, Kind::U8, "")
            ]
        );
        let o = Outer { p, q: [p] };
        let ob = o.encode();
        assert_eq!(&ob[outer::RESERVED..5], &[0; 5]);
        assert_eq!(Outer::decode(&ob), o);
        // Out of range: zeros, nothing written.
        assert_eq!(u32::get(&b, 14), 0);
        let mut short = [0u8; 3];
        p.put(&mut short, 0);
        assert_eq!(short, [0; 3]);
    }
}
