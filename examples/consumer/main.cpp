// Loads a robot description, builds the per-call workspace once, then evaluates inverse
// dynamics the way a control loop would.
#include <iostream>
#include <mindyn/description.hpp>
#include <mindyn/dynamics.hpp>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: consumer ROBOT.yaml\n";
    return 2;
  }
  try {
    const mindyn::Model model = mindyn::loadYaml(argv[1]);
    mindyn::Data data(model);  // all allocation happens here
    const int n = model.nq();
    const Eigen::VectorXd params = model.parameters();
    Eigen::VectorXd q = Eigen::VectorXd::Zero(n), dq = q, ddq = q, tau(n);
    mindyn::inverseDynamics(model, data, q, dq, ddq, params, {}, tau);  // real-time safe
    std::cout << model.name << ": " << n << " joints, tau(q0) = " << tau.transpose() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "consumer: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
