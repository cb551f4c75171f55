within StockbridgeDamper.Elements;
model MassSpringDamper "Mass on a linear spring and damper to ground, driven by a built-in force and an input force (e.g. from an element FMU): force in; motion out"
  parameter Real m(unit="kg", min=0) = 2 "Mass";
  parameter Real c(unit="N.s/m", min=0) = 10 "Viscous damping coefficient";
  parameter Real k(unit="N/m") = 5e4 "Linear stiffness";
  parameter Integer exc_type(min=0, max=3) = 2 "Built-in force: 0 off, 1 sine, 2 linear sweep, 3 log sweep; added to the input f";
  parameter Real exc_amplitude(unit="N") = 120 "Amplitude of the built-in force";
  parameter Real exc_f_start(unit="Hz", min=0) = 0 "Sine frequency or sweep start frequency";
  parameter Real exc_f_end(unit="Hz", min=0) = 60 "Sweep end frequency (held afterwards)";
  parameter Real exc_rate(unit="Hz/s", min=0) = 0.5 "Linear sweep rate";
  parameter Real exc_octaves_per_minute(unit="1/min") = 1 "Logarithmic sweep rate";
  parameter Real exc_t_ramp(unit="s", min=0) = 0 "Smooth amplitude ramp-in time (0: none)";
  input Real f(unit="N", start=0) "Force on the mass from a connected element, positive in +y direction";
  output Real y(unit="m") "Displacement of the mass";
  output Real v(unit="m/s") "Velocity of the mass";
  output Real a(unit="m/s2") "Acceleration of the mass";
  Components.Mass mass(m=m) "Mass";
  Components.SpringDamper springDamper(k=k, c=c) "Linear spring and damper to ground";
  Components.Fixed fixed "Ground";
  Sources.Force force "Total force on the mass";
  Sources.Excitation excitation(kind=exc_type, amplitude=exc_amplitude, f_start=exc_f_start, f_end=exc_f_end,
    rate=exc_rate, octaves_per_minute=exc_octaves_per_minute, t_ramp=exc_t_ramp) "Built-in force signal";
equation
  force.u = f + excitation.y;
  connect(force.flange, mass.flange);
  connect(springDamper.flange_b, mass.flange);
  connect(fixed.flange, springDamper.flange_a);
  y = mass.s;
  v = mass.v;
  a = der(mass.v);
  annotation(experiment(StartTime=0, StopTime=1, Interval=1e-4, Tolerance=1e-8));
end MassSpringDamper;
