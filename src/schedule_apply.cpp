// Applies one step's schedule events to a running simulation (docs/model.md 4, 3.9) in the order
// wind, forces, instances, remove, add (removal is applied after addition, which gives the same
// list: see below), through the live-control calls of Simulation.
#include <hmsm/schedule.h>

#include "model/input_limits.h"

#include <algorithm>

namespace hmsm {

Status apply_schedule_events(const Schedule& schedule, uint64_t step, Simulation& sim) {
    for (const ScheduleEvent& e : schedule.events) {
        if (e.step != step) continue;
        const std::string where = "schedule step " + std::to_string(e.step) + ": ";
        auto fail = [&](const Status& s) { return Status{s.code(), where + s.message()}; };
        if (e.wind) {
            Status s = sim.set_wind(e.wind->applied_to(sim.wind()));
            if (!s) return fail(s);
        }
        if (e.forces) {
            Status s = sim.set_force_fields(*e.forces);
            if (!s) return fail(s);
        }
        for (const InstanceChange& c : e.instances) {
            if (c.wind_scale) {
                Status s = sim.set_instance_wind_scale(c.instance, *c.wind_scale);
                if (!s) return fail(s);
            }
            if (c.wind_phase) {
                Status s = sim.set_instance_wind_phase(c.instance, *c.wind_phase);
                if (!s) return fail(s);
            }
            if (c.active) {
                Status s = sim.set_instance_active(c.instance, *c.active);
                if (!s) return fail(s);
            }
        }
        if (!e.add.empty()) {
            std::vector<Instance> added;
            for (const ScheduledInstance& a : e.add) {
                const std::optional<uint32_t> model = find_model(sim.scene(), a.model);
                if (!model)
                    return {ErrorCode::invalid_argument, where + "model \"" + detail::quote_input(a.model) + "\" is not one of the run's models"};
                Instance inst;
                inst.model = *model;
                inst.origin = a.origin;
                inst.yaw = a.yaw;
                inst.wind_scale = a.wind_scale;
                inst.wind_phase = a.wind_phase;
                inst.active = a.active;
                added.push_back(inst);
            }
            Status s = sim.add_instances(added);
            if (!s) return fail(s);
        }
        // Removal after addition: the indices name instances of the list before the event, which
        // are all still in front of the added ones, so the outcome is the survivors in their order
        // followed by the added instances, as if removal came first; and a simulation is never
        // left without instances in between (remove_instances keeps at least one).
        if (!e.remove.empty()) {
            Status s = sim.remove_instances(e.remove);
            if (!s) return fail(s);
        }
    }
    return {};
}

}  // namespace hmsm
