//! The slot enums, generated from the registry: `kinds::normal::Kind` (re-exported as
//! `NormalKind`), `kinds::tangential::Kind`, `kinds::rolling::Kind`, `kinds::cohesion::Kind`.
//! Each has `ALL` (registry order) and `spec()`.

/// Generates one module per slot holding its `Kind` enum.
#[doc(hidden)]
#[macro_export]
macro_rules! __define_kinds {
    ({} $( $slot:ident [ $( $variant:ident => $spec:path, $kernel:ty );* ] )*) => {
        $(
            #[doc = concat!("The `", stringify!($slot), "` slot of the contact law.")]
            pub mod $slot {
                #[doc = concat!(
                    "The effects registered for the `", stringify!($slot), "` slot of the ",
                    "contact law; [`Kind::spec`] gives an effect's user-facing name, parameters ",
                    "(with units and ranges) and LIGGGHTS equivalent."
                )]
                #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
                pub enum Kind {
                    $(
                        #[doc = concat!(
                            "The registry's `", stringify!($variant), "` effect; its physics ",
                            "and parameters are in [`Kind::spec`]."
                        )]
                        $variant
                    ),*
                }

                impl Kind {
                    /// Every effect of the slot, in registry order.
                    pub const ALL: &'static [Kind] = &[$( Kind::$variant ),*];

                    /// The effect's spec: name, parameters with units and ranges, and how their
                    /// values reach the pair constants.
                    pub fn spec(self) -> &'static $crate::contact::spec::EffectSpec {
                        match self {
                            $( Kind::$variant => &$spec ),*
                        }
                    }
                }
            }
        )*
    };
}

crate::__effect_registry!(__define_kinds {});

/// Runs `$body` with `$law` bound to the monomorphised [`Law`](super::Law) of a
/// [`ModelClass`](super::ModelClass): one `match` per slot, generated from the registry.
#[macro_export]
macro_rules! with_law {
    ($class:expr, |$law:ident| $body:expr) => {{
        // A `ModelClass` (not named here: this file must not import the file that uses it).
        let class = $class;
        $crate::__effect_registry!(__law_dispatch { { class, |$law| $body } [] })
    }};
}

/// The nested `match` behind [`with_law!`]: peels one slot of the registry at a time, collecting
/// the chosen kernel types, and builds the `Law` when every slot is chosen.
#[doc(hidden)]
#[macro_export]
macro_rules! __law_dispatch {
    (@next { $m:ident, |$law:ident| $body:expr } [$($t:ty),*] {}) => {{
        let $law = $crate::contact::law::Law::<$($t),*> {
            limit_force: $m.limit_force,
            ..::core::default::Default::default()
        };
        $body
    }};
    (@next $args:tt $chosen:tt { $slot:ident [ $( $variant:ident => $spec:path, $kernel:ty );* ] $($rest:tt)* }) => {
        $crate::__law_dispatch!(@match $args $chosen $slot [ $( $variant => $kernel );* ] { $($rest)* })
    };
    (@match { $m:ident, |$law:ident| $body:expr } $chosen:tt $slot:ident [ $( $variant:ident => $kernel:ty );* ] $rest:tt) => {
        match $m.$slot {
            $(
                $crate::contact::kinds::$slot::Kind::$variant => {
                    $crate::__law_dispatch!(@append { $m, |$law| $body } $chosen $kernel, $rest)
                }
            )*
        }
    };
    (@append $args:tt [$($t:ty),*] $kernel:ty, $rest:tt) => {
        $crate::__law_dispatch!(@next $args [$($t,)* $kernel] $rest)
    };
    ({ $args:tt $chosen:tt } $($rest:tt)*) => {
        $crate::__law_dispatch!(@next $args $chosen { $($rest)* })
    };
}
