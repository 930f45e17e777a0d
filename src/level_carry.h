// How a level-of-detail switch carries an instance's chain state from one run model to another
// (docs/model.md 3.12, docs/driving.md, levels of detail): the chains both levels keep take
// their values element for element, and the chains the new level unfolds start rigid with their
// parent. A level keeps the full model's chains in the full model's order, so the kept chains
// make runs that ascend in old and in new chains alike.
#pragma once

#include "backend.h"

#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace hmsm::detail {

/// The carry from one run model (old) to another (new), the same for every instance switched
/// between them.
struct LevelCarry {
    /// Per new chain: the old chain that keeps the same full-model chain, or -1 (unfolded).
    std::vector<int32_t> old_chain;
    /// Q_c per new chain: an unfolded chain is at rest relative to its parent, T = Q_c.
    std::vector<glm::dmat3> rest_rotation;
    /// Runs of new chains that take old chains neighbouring in both models: src is the run's
    /// first old chain, dst its first new chain (relative to the instance's first chain).
    std::vector<ElementMove> kept;
    /// Runs of unfolded new chains (relative to the instance's first chain).
    std::vector<ElementRange> unfolded;
};

/// The carry between run models whose chains keep the full-model chains `old_source` and
/// `new_source` (each ascending), `new_rest` the new model's Q_c per chain.
LevelCarry make_level_carry(const std::vector<int32_t>& old_source, const std::vector<int32_t>& new_source,
                            std::vector<glm::dmat3> new_rest);

/// The values of chain-scope buffer `id` (`per` scalars a chain) of a chain at rest relative to
/// its parent: state, force and load 0, T = Q (the pose is recomputed), written into `chain`
/// (zero on entry).
template <class V>
void rest_chain(V* chain, BufferId id, const glm::dmat3& rest_rotation) {
    if (id != BufferId::chain_local) return;  // T = Q Rz(0) Rx(0): rigid with the parent
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row) chain[4 * col + row] = V(rest_rotation[col][row]);
}

/// Every chain of a run model whose chains' Q_c are `rest_rotation` at rest (rest_chain), back
/// to back: the template the unfolded chains of instances switched into it are copied from on
/// the device.
template <class V>
std::vector<V> rest_chains(const std::vector<glm::dmat3>& rest_rotation, uint32_t per, BufferId id) {
    std::vector<V> values(rest_rotation.size() * per, V(0));
    for (size_t j = 0; j < rest_rotation.size(); ++j) rest_chain(values.data() + j * per, id, rest_rotation[j]);
    return values;
}

/// Carries one switched instance's values of chain-scope buffer `id` (`per` scalars a chain)
/// into `into` (its new chains, zero on entry): each chain takes the values of the old chain the
/// carry names, at old(c) for old chain c, or those of a chain at rest (rest_chain).
template <class V, class Old>
void carry_switched(V* into, const LevelCarry& carry, uint32_t per, BufferId id, Old&& old) {
    for (size_t j = 0; j < carry.old_chain.size(); ++j) {
        V* chain = into + j * per;
        if (carry.old_chain[j] >= 0) std::copy_n(old(carry.old_chain[j]), per, chain);
        else rest_chain(chain, id, carry.rest_rotation[j]);
    }
}

}  // namespace hmsm::detail
