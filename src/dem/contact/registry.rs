//! Every physical effect mbgc knows, by slot of the contact law: one line each,
//! `Variant => SPEC, Kernel;` with `SPEC` the effect's [`EffectSpec`](super::spec::EffectSpec)
//! (name, parameters) and `Kernel` the type that computes it. Effects may share a kernel (the
//! power-law dashpots, the tangential variants): the force loop is compiled once per distinct
//! combination of kernels, not per effect.
//!
//! Registering an effect is one line here (after writing its file; see the README, "Adding a
//! physical effect"). The slot enums ([`NormalKind`](super::NormalKind), ...) and the dispatch
//! ([`with_law!`](crate::with_law)) are generated from this list.

/// Calls `$callback! { { $args } normal [...] tangential [...] rolling [...] cohesion [...] }`.
#[doc(hidden)]
#[macro_export]
macro_rules! __effect_registry {
    ($callback:ident { $($args:tt)* }) => {
        $crate::$callback! { { $($args)* }
            normal [
                Hertz => $crate::dem::contact::hertz::SPEC, $crate::dem::contact::hertz::Hertz;
                Tsuji => $crate::dem::contact::power_damped::TSUJI, $crate::dem::contact::power_damped::PowerDamped;
                KuwabaraKono => $crate::dem::contact::power_damped::KUWABARA_KONO, $crate::dem::contact::power_damped::PowerDamped;
                PowerDamped => $crate::dem::contact::power_damped::POWER_DAMPED, $crate::dem::contact::power_damped::PowerDamped
            ]
            tangential [
                Mindlin => $crate::dem::contact::mindlin::SPEC, $crate::dem::contact::mindlin::HistorySpring;
                StrictCoulomb => $crate::dem::contact::mindlin::STRICT_COULOMB, $crate::dem::contact::mindlin::HistorySpring;
                LinearSpring => $crate::dem::contact::mindlin::LINEAR_SPRING, $crate::dem::contact::mindlin::HistorySpring
            ]
            rolling [
                None => $crate::dem::contact::none::NO_ROLLING, $crate::dem::contact::none::NoRolling;
                Epsd2 => $crate::dem::contact::epsd2::SPEC, $crate::dem::contact::epsd2::Epsd2;
                Cdt => $crate::dem::contact::cdt::SPEC, $crate::dem::contact::cdt::Cdt
            ]
            cohesion [
                None => $crate::dem::contact::none::NO_COHESION, $crate::dem::contact::none::NoCohesion;
                Sjkr => $crate::dem::contact::sjkr::SPEC, $crate::dem::contact::sjkr::Sjkr
            ]
        }
    };
}
