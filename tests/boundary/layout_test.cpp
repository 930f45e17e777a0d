// Public struct layouts do not depend on the consumer's GLM_FORCE_* settings.
#include "layout_fields.h"

#include <gtest/gtest.h>

TEST(Layout, PublicStructsIgnoreConsumerGlmSettings) {
    const std::vector<size_t> library = layout_default(), consumer = layout_forced();
    ASSERT_EQ(library.size(), consumer.size());
    for (size_t i = 0; i < library.size(); ++i) EXPECT_EQ(library[i], consumer[i]) << "value " << i;
}

TEST(Layout, SceneBuiltUnderForcedGlmSimulatesIdentically) {
    const std::vector<double> library = simulate_default(), consumer = simulate_forced();
    ASSERT_FALSE(library.empty());
    EXPECT_EQ(library, consumer);
}
