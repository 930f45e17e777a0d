#include <hmsm/options.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace hmsm;

namespace {
constexpr double pi = std::numbers::pi;
}

TEST(Wind, ProfilesMatchTheirFormulas) {
    for (double x : {0.0, 0.013, 0.1, 0.37, 0.5, 0.81, 1.0, 1.44, 1.999}) {
        double y1 = std::cos(pi * x) * std::cos(3 * pi * x) * std::cos(5 * pi * x) *
                        std::cos(7 * pi * x) - 0.1 * std::sin(25 * pi * x);
        double y2 = (std::sin(pi * x) + std::sin(3 * pi * x) + std::sin(5 * pi * x) +
                     std::sin(7 * pi * x)) / 4.0;
        double c2 = std::cos(pi * x) * std::cos(pi * x);
        double y3 = c2 * std::cos(3 * pi * x) * std::cos(5 * pi * x) - 0.02 * std::sin(25 * pi * x);
        double y4 = c2 * std::cos(3 * pi * x) * std::cos(5 * pi * x) - 0.1 * std::sin(25 * pi * x);
        EXPECT_NEAR(wind_profile_value(WindProfile::y1, x), y1, 1e-14) << x;
        EXPECT_NEAR(wind_profile_value(WindProfile::y2, x), y2, 1e-14) << x;
        EXPECT_NEAR(wind_profile_value(WindProfile::y3, x), y3, 1e-14) << x;
        EXPECT_NEAR(wind_profile_value(WindProfile::y4, x), y4, 1e-14) << x;
        EXPECT_EQ(wind_profile_value(WindProfile::constant, x), 1.0);
        EXPECT_EQ(wind_profile_value(WindProfile::none, x), 0.0);
    }
}

TEST(Wind, KnownValues) {
    EXPECT_NEAR(wind_profile_value(WindProfile::y1, 0.0), 1.0, 1e-15);
    EXPECT_NEAR(wind_profile_value(WindProfile::y2, 0.5), 0.0, 1e-15);  // 1 - 1 + 1 - 1
    EXPECT_NEAR(wind_profile_value(WindProfile::y3, 0.0), 1.0, 1e-15);
    EXPECT_NEAR(wind_profile_value(WindProfile::y4, 1.0 / 50.0),
                std::pow(std::cos(pi / 50), 2) * std::cos(3 * pi / 50) * std::cos(5 * pi / 50) - 0.1,
                1e-14);
}

TEST(Wind, ProfilesHavePeriodTwo) {
    for (WindProfile p : {WindProfile::y1, WindProfile::y2, WindProfile::y3, WindProfile::y4})
        for (double x : {0.1, 0.77, 1.3})
            EXPECT_NEAR(wind_profile_value(p, x), wind_profile_value(p, x + 2.0), 1e-12);
}

TEST(Wind, DirectionStrengthFrequencyAndFront) {
    Wind wind;
    wind.profile = WindProfile::y2;
    wind.direction = {0, 0, 2};  // normalized when used
    wind.strength = 3.0;
    wind.frequency = 0.25;
    glm::dvec3 w = wind_at(wind, {5, 0, 7}, 2.0);
    EXPECT_NEAR(w.x, 0.0, 1e-15);
    EXPECT_NEAR(w.z, 3.0 * wind_profile_value(WindProfile::y2, 0.5), 1e-14);
    // A travelling front delays the wind by (o.d)/v.
    wind.front_speed = 4.0;
    glm::dvec3 origin(1, 0, 8);  // o.d = 8 -> delay 2 s
    EXPECT_NEAR(wind_phase(wind, origin), -0.25 * 8.0 / 4.0, 1e-15);
    EXPECT_NEAR(wind_at(wind, origin, 3.0).z, wind_at(wind, {0, 0, 0}, 1.0).z, 1e-14);
}

TEST(Wind, RejectsBadValues) {
    Wind wind;
    wind.direction = {0, 0, 0};
    EXPECT_EQ(validate(wind).code(), ErrorCode::invalid_argument);
    wind = {};
    wind.frequency = -1;
    EXPECT_FALSE(validate(wind).ok());
    wind = {};
    wind.front_speed = -1;
    EXPECT_FALSE(validate(wind).ok());
    wind = {};
    wind.strength = NAN;
    EXPECT_FALSE(validate(wind).ok());
    EXPECT_TRUE(validate(Wind{}).ok());
}

TEST(Parameters, ValidRanges) {
    EXPECT_TRUE(validate(Parameters{}).ok());
    auto bad = [](auto mutate) {
        Parameters p;
        mutate(p);
        Status s = validate(p);
        EXPECT_EQ(s.code(), ErrorCode::invalid_argument);
        return s.message();
    };
    EXPECT_NE(bad([](Parameters& p) { p.dt = 0; }).find("dt"), std::string::npos);
    EXPECT_NE(bad([](Parameters& p) { p.density = -1; }).find("density"), std::string::npos);
    EXPECT_NE(bad([](Parameters& p) { p.stiffness = 0; }).find("stiffness"), std::string::npos);
    EXPECT_NE(bad([](Parameters& p) { p.damping_ratio = -0.1; }).find("damping"), std::string::npos);
    EXPECT_NE(bad([](Parameters& p) { p.wind_gain = -1; }).find("wind_gain"), std::string::npos);
    EXPECT_NE(bad([](Parameters& p) { p.max_angle = 2.0; }).find("max_angle"), std::string::npos);
    EXPECT_NE(bad([](Parameters& p) { p.dt = INFINITY; }).find("dt"), std::string::npos);
    ModelOptions o;
    o.ring_sides = 2;
    EXPECT_FALSE(validate(o).ok());
    o = {};
    o.fix_weight = 1.5;
    EXPECT_FALSE(validate(o).ok());
    o = {};
    o.max_chain_segments = -1;
    EXPECT_FALSE(validate(o).ok());
}
