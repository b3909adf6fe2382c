//! The names a run's option values go by on the command line and in its output files. An option
//! enum declared through [`named_enum!`] names each of its values (and any aliases) beside it
//! and implements [`Named`]: its `name`, `Display` and `from_name`, and each value's doc comment,
//! from which the command line builds its parser and `--help` (the core itself parses no
//! command line).

/// An option enum whose values go by names (`--reuse exact`, `"reuse": "exact"`), declared
/// through [`named_enum!`].
pub trait Named: Copy + Sized + 'static {
    /// Every value, in declaration order (the order `--help` lists them in).
    const VALUES: &'static [Self];

    /// The value's name.
    fn name(self) -> &'static str;

    /// Other names the value is accepted by.
    fn aliases(self) -> &'static [&'static str];

    /// The value's doc comment, its lines joined by `\n` (each as written, with the space
    /// after `///`).
    fn doc(self) -> &'static str;

    /// The value named `name` or one of its aliases.
    fn from_name(name: &str) -> Option<Self> {
        Self::VALUES.iter().copied().find(|v| v.name() == name || v.aliases().contains(&name))
    }
}

/// Declares an option enum of unit variants, each followed by its name (`Variant = "name"`) and
/// any aliases (`| "alias"`), and implements [`Named`] and `Display` (the name) for it.
/// Attributes and doc comments go through to the enum and its variants.
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $ty:ident {
            $($(#[$($attr:tt)*])* $variant:ident = $name:literal $(| $alias:literal)*),* $(,)?
        }
    ) => {
        $(#[$meta])*
        $vis enum $ty {
            $($(#[$($attr)*])* $variant,)*
        }

        impl $crate::names::Named for $ty {
            const VALUES: &'static [Self] = &[$($ty::$variant),*];

            fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)*
                }
            }

            fn aliases(self) -> &'static [&'static str] {
                match self {
                    $($ty::$variant => &[$($alias),*],)*
                }
            }

            fn doc(self) -> &'static str {
                match self {
                    $($ty::$variant => concat!($($crate::names::named_enum!(@doc $($attr)*)),*),)*
                }
            }
        }

        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::names::Named::name(*self))
            }
        }
    };
    // One attribute's part of a variant's doc: a doc comment's line, nothing for the others.
    (@doc doc = $line:literal) => { concat!($line, "\n") };
    (@doc $($other:tt)*) => { "" };
}
pub(crate) use named_enum;

#[cfg(test)]
mod tests {
    use super::Named;

    named_enum! {
        /// A test enum.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        enum Shade {
            /// Light.
            ///
            /// Second paragraph.
            Light = "light",
            #[default]
            Dark = "dark" | "black" | "night",
            /// Grey, between.
            Grey = "grey",
        }
    }

    #[test]
    fn values_go_by_their_names_and_aliases() {
        assert_eq!(Shade::VALUES, [Shade::Light, Shade::Dark, Shade::Grey]);
        for &v in Shade::VALUES {
            assert_eq!(Shade::from_name(v.name()), Some(v));
            assert_eq!(v.to_string(), v.name());
        }
        assert_eq!(Shade::from_name("night"), Some(Shade::Dark));
        assert_eq!(Shade::from_name("Dark"), None);
        assert_eq!(Shade::default(), Shade::Dark);
    }

    #[test]
    fn docs_keep_their_lines() {
        assert_eq!(Shade::Light.doc(), " Light.\n\n Second paragraph.\n");
        assert_eq!(Shade::Dark.doc(), "");
        assert_eq!(Shade::Grey.doc(), " Grey, between.\n");
    }
}
