//! Every physical effect mbgc knows, by slot of the contact law: one line each,
//! `Variant => SPEC, Kernel;` with `SPEC` the effect's [`EffectSpec`](super::spec::EffectSpec)
//! (name, parameters) and `Kernel` the type that computes it. Effects may share a kernel (the
//! power-law dashpots, the tangential variants): the force loop is compiled once per distinct
//! combination of kernels, not per effect.
//!
//! Registering an effect is one line here (after writing its file; see "Add a physical effect"
//! in the guide, docs/guide/src/extending.md). The slot enums
//! ([`NormalKind`](super::NormalKind), ...) and the dispatch ([`with_law!`](crate::with_law)) are
//! generated from this list.

/// Calls `$callback! { { $args } normal [...] tangential [...] rolling [...] cohesion [...] }`.
#[doc(hidden)]
#[macro_export]
macro_rules! __effect_registry {
    ($callback:ident { $($args:tt)* }) => {
        $crate::$callback! { { $($args)* }
            normal [
                Hertz => $crate::contact::hertz::SPEC, $crate::contact::hertz::Hertz;
                Tsuji => $crate::contact::power_damped::TSUJI, $crate::contact::power_damped::PowerDamped;
                KuwabaraKono => $crate::contact::power_damped::KUWABARA_KONO, $crate::contact::power_damped::PowerDamped;
                PowerDamped => $crate::contact::power_damped::POWER_DAMPED, $crate::contact::power_damped::PowerDamped
            ]
            tangential [
                Mindlin => $crate::contact::mindlin::SPEC, $crate::contact::mindlin::HistorySpring;
                StrictCoulomb => $crate::contact::mindlin::STRICT_COULOMB, $crate::contact::mindlin::HistorySpring;
                LinearSpring => $crate::contact::mindlin::LINEAR_SPRING, $crate::contact::mindlin::HistorySpring
            ]
            rolling [
                None => $crate::contact::none::NO_ROLLING, $crate::contact::none::NoRolling;
                Epsd2 => $crate::contact::epsd2::SPEC, $crate::contact::epsd2::Epsd2;
                Cdt => $crate::contact::cdt::SPEC, $crate::contact::cdt::Cdt
            ]
            cohesion [
                None => $crate::contact::none::NO_COHESION, $crate::contact::none::NoCohesion;
                Sjkr => $crate::contact::sjkr::SPEC, $crate::contact::sjkr::Sjkr
            ]
        }
    };
}
