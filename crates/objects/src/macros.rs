//! The table macros: one line per object, sub-index 0 added for ARRAY/RECORD.

/// A VAR: `var!(profile, index, name, type, access, pdo)`.
macro_rules! var {
    ($p:ident, $i:expr, $n:expr, $t:ident, $a:ident, $pdo:expr) => {
        Def {
            first: $i,
            last: $i,
            name: $n,
            kind: Kind::Var,
            profile: Standard::$p,
            subs: &[SubDef { first: 0, last: 0, name: $n, data_type: T::$t, access: A::$a, pdo: $pdo }],
        }
    };
}

/// An ARRAY or RECORD (or a run of them, `first..last`): sub-index 0 is
/// added as `Highest sub-index supported` (UNSIGNED8, ro) unless `$zero` names it.
macro_rules! obj {
    ($p:ident, $k:ident, $i:expr, $j:expr, $n:expr, $zero:expr, $za:ident,
     [ $( ($f:expr, $l:expr, $sn:expr, $t:ident, $a:ident, $pdo:expr) ),* $(,)? ]) => {
        Def {
            first: $i,
            last: $j,
            name: $n,
            kind: Kind::$k,
            profile: Standard::$p,
            subs: &[
                SubDef { first: 0, last: 0, name: $zero, data_type: T::Unsigned8, access: A::$za, pdo: false },
                $( SubDef { first: $f, last: $l, name: $sn, data_type: T::$t, access: A::$a, pdo: $pdo } ),*
            ],
        }
    };
}

pub(crate) const HS: &str = "Highest sub-index supported";
pub(crate) const NE: &str = "Number of entries";
