// Per-stage timings, counts and warnings of one frame, reported by the CLI (--stats) and the Python API.
#pragma once
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace meniscus {

struct PipelineStats {
    std::vector<std::pair<std::string, double>> stage_seconds;  // in pipeline order
    std::vector<std::pair<std::string, double>> counts;         // particles, triangles, ...
    std::vector<std::string> warnings;

    void add_seconds(const std::string& stage, double seconds) {
        for (auto& entry : stage_seconds)
            if (entry.first == stage) { entry.second += seconds; return; }
        stage_seconds.emplace_back(stage, seconds);
    }
    void set_count(const std::string& name, double value) {
        for (auto& entry : counts)
            if (entry.first == name) { entry.second = value; return; }
        counts.emplace_back(name, value);
    }
    double count(const std::string& name, double missing = 0) const {
        for (const auto& entry : counts)
            if (entry.first == name) return entry.second;
        return missing;
    }
    double total_seconds() const {
        double total = 0;
        for (const auto& entry : stage_seconds) total += entry.second;
        return total;
    }
};

// Adds the time from construction to destruction (or stop()) to a stage.
class StageTimer {
public:
    StageTimer(PipelineStats* stats, std::string stage) : stats_(stats), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
    ~StageTimer() { stop(); }
    void stop() {
        if (!stats_) return;
        stats_->add_seconds(stage_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
        stats_ = nullptr;
    }

private:
    PipelineStats* stats_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace meniscus
