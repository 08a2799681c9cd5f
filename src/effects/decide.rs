//! What becomes of each effect a scene asks for: on, or off with the
//! reason, from its kind's verdict on this scene and world and the effects
//! it needs.

use super::kind::{Verdict, WorldContent};
use super::registry::kind_of;
use super::requested::Effects;
use crate::scene::effect::{Effect, EffectDecision};

/// Decides every effect: requested and backed by the world's data means
/// on. `force` (tests only) keeps an effect on although the world lacks
/// its data, to show its path changes nothing there.
pub fn decide(fx: &Effects, content: &WorldContent, force: bool) -> Vec<EffectDecision> {
    let mut decisions: Vec<EffectDecision> = Effect::ALL
        .into_iter()
        .map(|effect| {
            let requested = fx.is_on(effect);
            let how = if fx.is_named(effect) { "" } else { " (default)" };
            let (on, reason) = if !requested {
                (false, format!("not requested{how}"))
            } else {
                match kind_of(effect).verdict(fx, content, force) {
                    Verdict::On => (true, format!("requested{how}")),
                    Verdict::OnWith(note) => (true, format!("requested{how}: {note}")),
                    Verdict::Forced(why) => (true, format!("forced on (test override) although {why}")),
                    Verdict::Off(why) => (false, format!("requested, but {why}")),
                }
            };
            EffectDecision { effect, requested, on, reason }
        })
        .collect();
    // Whatever switched a needed effect off takes its dependants with it.
    for i in 0..decisions.len() {
        let unmet = kind_of(decisions[i].effect)
            .needs()
            .iter()
            .find(|(need, _)| !decisions.iter().any(|d| d.effect == *need && d.on));
        if let (true, Some((_, why))) = (decisions[i].on, unmet) {
            decisions[i].on = false;
            decisions[i].reason = format!("requested, but {why}");
        }
    }
    decisions
}
