within StockbridgeDamper.Components;
model CoulombFriction "Regularised Coulomb friction: f = F_c*tanh(v_rel/v_s); F_c = 0 switches it off"
  extends Interfaces.PartialCompliant;
  parameter Real F_c(unit="N") = 0 "Friction force level";
  parameter Real v_s(unit="m/s") = 1e-3 "Regularisation velocity (width of the tanh)";
equation
  f = F_c*tanh(v_rel/v_s);
end CoulombFriction;
